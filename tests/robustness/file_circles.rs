//! No circle among the files of a crate (issue #14): if `a.rs` uses `b.rs`, nothing `b.rs`
//! uses, directly or through other files, uses `a.rs`. A circle means two files that cannot
//! be read, tested or moved apart; layers stay layers only if this holds.
//!
//! Each source file is parsed with `syn`; a file uses another when a path in it (`use`
//! items, types, expressions, patterns: every `syn::Path` outside test and doc-only items)
//! names an item of the other's module, or of a module the other's `pub use` re-exports it
//! from (`experiments::Error` is `experiments/error.rs`). A `pub use` is a use of what it
//! re-exports, but for a folder's face: `mod.rs` (or `lib.rs`) re-exporting its own files'
//! items, which those files may use, is the module tree's structure, as its `mod` lines are;
//! where the face itself names such an item (`pub use error::Error;` then `-> Error`), it
//! uses that file. Imports are followed by the name they bring in (`use a as b;` then
//! `b::x`). A `use` inside a function counts as well; test and doc-only items are skipped at any depth.
//! Paths inside macro calls (`format!`, `matches!`) and method calls (resolved by type) are
//! not seen: a circle made only of those would be missed.
//!
//! `src/` and `runtime/src` hold to it strictly, and `codegen/src` but for two folders whose
//! files may also use the folder's `mod.rs`: `front/lower/`, where the front end's `Lowerer`
//! is one struct whose `impl` blocks fill the folder's files, one topic each, its fields'
//! types (a body's record, a typed expression, a pending load) living with their topic; and
//! `ir/`, whose `Model` holds the plausibility requirements `plausible.rs` states over the
//! model's expressions. The struct names its fields' types while each file names the struct.
//! Calls between `impl` blocks are method calls, which a path does not show either.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use syn::visit::Visit;

/// A module path inside the crate (`["experiments", "leg"]`), the crate root being `[]`.
type Module = Vec<String>;

/// Every `.rs` file below `root`, by module path.
fn module_files(root: &Path) -> BTreeMap<Module, PathBuf> {
    let mut files = BTreeMap::new();
    let mut folders = vec![root.to_path_buf()];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                folders.push(path);
            } else if path.extension().is_some_and(|x| x == "rs") {
                let relative = path.strip_prefix(root).unwrap().with_extension("");
                let mut module: Module = relative
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                // A `main.rs` beside a `lib.rs` is the root of another crate (the binary).
                if module.last().is_some_and(|m| m == "main") && folder.join("lib.rs").exists() {
                    continue;
                }
                if matches!(
                    module.last().map(String::as_str),
                    Some("mod" | "lib" | "main")
                ) {
                    module.pop();
                }
                let file = path.display().to_string();
                let twin = files.insert(module, path);
                assert!(twin.is_none(), "two files of one module: {file}, {twin:?}");
            }
        }
    }
    files
}

/// Whether an item is compiled only for tests or documentation.
fn test_or_doc_only(attributes: &[syn::Attribute]) -> bool {
    attributes.iter().any(|attribute| {
        attribute.path().is_ident("cfg") && {
            let text = attribute.meta.require_list().map(|l| l.tokens.to_string());
            matches!(text.as_deref(), Ok("test" | "doc"))
        }
    })
}

fn attributes(item: &syn::Item) -> &[syn::Attribute] {
    match item {
        syn::Item::Use(i) => &i.attrs,
        syn::Item::Mod(i) => &i.attrs,
        syn::Item::Fn(i) => &i.attrs,
        syn::Item::Impl(i) => &i.attrs,
        syn::Item::Struct(i) => &i.attrs,
        syn::Item::Enum(i) => &i.attrs,
        syn::Item::Const(i) => &i.attrs,
        syn::Item::Static(i) => &i.attrs,
        syn::Item::Trait(i) => &i.attrs,
        syn::Item::Type(i) => &i.attrs,
        syn::Item::Macro(i) => &i.attrs,
        _ => &[],
    }
}

/// One leaf of a `use` tree: the path it names and the name it is known by in the file.
struct UseLeaf {
    path: Vec<String>,
    name: String,
}

/// The leaves of a `use` tree (`a::{b, c::d as e}` → `a::b` as `b`, `a::c::d` as `e`); a
/// `self` leaf names the module itself, a glob the module it reads (known by no name).
fn use_paths(tree: &syn::UseTree, prefix: &mut Vec<String>, out: &mut Vec<UseLeaf>) {
    let mut leaf = |path: Vec<String>, name: String| out.push(UseLeaf { path, name });
    match tree {
        syn::UseTree::Path(p) => {
            prefix.push(p.ident.to_string());
            use_paths(&p.tree, prefix, out);
            prefix.pop();
        }
        syn::UseTree::Name(n) if n.ident == "self" => {
            leaf(prefix.clone(), prefix.last().cloned().unwrap_or_default())
        }
        syn::UseTree::Name(n) => leaf(
            [prefix.clone(), vec![n.ident.to_string()]].concat(),
            n.ident.to_string(),
        ),
        syn::UseTree::Rename(r) => leaf(
            [prefix.clone(), vec![r.ident.to_string()]].concat(),
            r.rename.to_string(),
        ),
        syn::UseTree::Glob(_) => leaf(prefix.clone(), String::new()),
        syn::UseTree::Group(g) => g.items.iter().for_each(|t| use_paths(t, prefix, out)),
    }
}

/// The paths a file writes outside its top-level `use` items (those are read apart): a `use`
/// inside a function counts as the paths it names.
#[derive(Default)]
struct Paths(Vec<Vec<String>>);

impl<'a> Visit<'a> for Paths {
    fn visit_path(&mut self, path: &'a syn::Path) {
        self.0
            .push(path.segments.iter().map(|s| s.ident.to_string()).collect());
        syn::visit::visit_path(self, path);
    }
    fn visit_item_use(&mut self, item: &'a syn::ItemUse) {
        let mut leaves = Vec::new();
        use_paths(&item.tree, &mut Vec::new(), &mut leaves);
        self.0.extend(leaves.into_iter().map(|leaf| leaf.path));
    }
    // `pub(crate)`, `pub(super)`: where an item is seen from, not a use.
    fn visit_vis_restricted(&mut self, _: &'a syn::VisRestricted) {}
    // Test and doc-only items at any depth: a module, a function in a block, a method.
    fn visit_item(&mut self, item: &'a syn::Item) {
        if !test_or_doc_only(attributes(item)) {
            syn::visit::visit_item(self, item);
        }
    }
    fn visit_impl_item_fn(&mut self, method: &'a syn::ImplItemFn) {
        if !test_or_doc_only(&method.attrs) {
            syn::visit::visit_impl_item_fn(self, method);
        }
    }
}

/// One parsed file: what it writes, and what it imports or re-exports.
struct Source {
    module: Module,
    uses: Vec<UseLeaf>,
    reexports: Vec<UseLeaf>,
    paths: Vec<Vec<String>>,
}

fn parse(module: &Module, path: &Path) -> Source {
    let text = std::fs::read_to_string(path).unwrap();
    let file = syn::parse_file(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let (mut uses, mut reexports, mut paths) = (Vec::new(), Vec::new(), Paths::default());
    for item in file
        .items
        .iter()
        .filter(|i| !test_or_doc_only(attributes(i)))
    {
        match item {
            syn::Item::Use(u) if matches!(u.vis, syn::Visibility::Inherited) => {
                use_paths(&u.tree, &mut Vec::new(), &mut uses)
            }
            syn::Item::Use(u) => use_paths(&u.tree, &mut Vec::new(), &mut reexports),
            item => paths.visit_item(item),
        }
    }
    Source {
        module: module.clone(),
        uses,
        reexports,
        paths: paths.0,
    }
}

/// The crate-absolute form of a path written in `source`, if it starts at `crate`, `self`,
/// `super`, a name the file imported, or a child module of the file's named with what
/// follows it.
fn absolute(
    source: &Source,
    path: &[String],
    imported: &BTreeMap<String, Vec<String>>,
    files: &BTreeMap<Module, PathBuf>,
) -> Option<Module> {
    let first = path.first()?;
    // A file's module is its folder for `mod.rs`, so `self` and `super` count alike in both:
    // in `a/b.rs` and in `a/b/mod.rs`, `self::x` is `a::b::x` and `super::x` is `a::x`.
    let here = source.module.clone();
    let rest = |n: usize| path[n..].to_vec();
    Some(match first.as_str() {
        "crate" => rest(1),
        "self" => [here, rest(1)].concat(),
        "super" => {
            let supers = path.iter().take_while(|s| *s == "super").count();
            let keep = source.module.len().checked_sub(supers)?;
            [source.module[..keep].to_vec(), rest(supers)].concat()
        }
        name if imported.contains_key(name) => [imported[name].clone(), rest(1)].concat(),
        // A lone name is a value or a type, never the module: `match hinge` in
        // `transform/mod.rs` is a variable, not `transform/hinge.rs`.
        name if path.len() > 1
            && files.contains_key(&[here.clone(), vec![name.into()]].concat()) =>
        {
            [here, path.to_vec()].concat()
        }
        _ => return None,
    })
}

/// The file an absolute path lands in: its longest module prefix that is a file, or the
/// file that module re-exports the next name from.
fn file_of(
    path: &[String],
    files: &BTreeMap<Module, PathBuf>,
    reexported: &BTreeMap<(Module, String), Module>,
) -> Option<Module> {
    (0..=path.len()).rev().find_map(|n| {
        let module = path[..n].to_vec();
        files.contains_key(&module).then(|| {
            match path
                .get(n)
                .and_then(|next| reexported.get(&(module.clone(), next.clone())))
            {
                Some(child) => child.clone(),
                None => module,
            }
        })
    })
}

/// Which file uses which, over the crate whose sources are under `root`.
fn uses_graph(root: &Path) -> BTreeMap<Module, BTreeSet<Module>> {
    let files = module_files(root);
    let sources: Vec<Source> = files.iter().map(|(m, p)| parse(m, p)).collect();
    // `pub use …::Name` in a module: `module::Name` is in the file the path lands in; again
    // until nothing changes, for re-exports of re-exports.
    let mut reexported = BTreeMap::new();
    loop {
        let before = reexported.clone();
        for source in &sources {
            for leaf in &source.reexports {
                let full = absolute(source, &leaf.path, &BTreeMap::new(), &files);
                if let Some(file) = full.and_then(|f| file_of(&f, &files, &reexported)) {
                    reexported.insert((source.module.clone(), leaf.name.clone()), file);
                }
            }
        }
        if reexported == before {
            break;
        }
    }
    let mut graph = BTreeMap::new();
    for source in &sources {
        let none = BTreeMap::new();
        // Names the file imported or re-exported, by the name it knows them by.
        let mut imported = BTreeMap::new();
        let mut used = BTreeSet::new();
        // A module's face (its file re-exporting its own child files' items, which those
        // files may use) is the module tree's structure, as its `mod` lines are; every other
        // `use` or re-export is a use. Either way the names it brings in count where they are
        // written.
        let own_child = |full: &Module| {
            let depth = source.module.len();
            full.len() > depth + 1
                && full.starts_with(&source.module)
                && files.contains_key(&full[..=depth])
        };
        for (leaf, reexport) in source
            .uses
            .iter()
            .map(|leaf| (leaf, false))
            .chain(source.reexports.iter().map(|leaf| (leaf, true)))
        {
            let Some(full) = absolute(source, &leaf.path, &none, &files) else {
                continue;
            };
            if !leaf.name.is_empty() {
                imported.insert(leaf.name.clone(), full.clone());
            }
            if !(reexport && own_child(&full)) {
                used.extend(file_of(&full, &files, &reexported));
            }
        }
        for path in &source.paths {
            if let Some(full) = absolute(source, path, &imported, &files) {
                used.extend(file_of(&full, &files, &reexported));
            }
        }
        used.remove(&source.module);
        graph.insert(source.module.clone(), used);
    }
    graph
}

/// A circle of the graph, as the files along it, if there is one.
fn circle(graph: &BTreeMap<Module, BTreeSet<Module>>) -> Option<Vec<Module>> {
    // Depth-first search; a use of a file still on the stack closes a circle.
    fn visit(
        node: &Module,
        graph: &BTreeMap<Module, BTreeSet<Module>>,
        stack: &mut Vec<Module>,
        done: &mut BTreeSet<Module>,
    ) -> Option<Vec<Module>> {
        if let Some(start) = stack.iter().position(|m| m == node) {
            return Some([&stack[start..], std::slice::from_ref(node)].concat());
        }
        if done.contains(node) {
            return None;
        }
        stack.push(node.clone());
        for next in graph.get(node).into_iter().flatten() {
            if let Some(found) = visit(next, graph, stack, done) {
                return Some(found);
            }
        }
        stack.pop();
        done.insert(node.clone());
        None
    }
    let mut done = BTreeSet::new();
    graph
        .keys()
        .find_map(|node| visit(node, graph, &mut Vec::new(), &mut done))
}

/// Checks the crate under `crate_sources`; a file in one of `impl_folders` may also use that
/// folder's `mod.rs` (see the module's text).
fn assert_no_circle(crate_sources: &str, impl_folders: &[&str]) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join(crate_sources);
    let mut graph = uses_graph(&root);
    for (file, used) in graph.iter_mut() {
        let parent = file[..file.len().saturating_sub(1)].to_vec();
        if impl_folders.contains(&parent.join("/").as_str()) {
            used.remove(&parent);
        }
    }
    assert!(graph.len() > 5, "{crate_sources}: too few files read");
    if let Some(files) = circle(&graph) {
        let shown: Vec<String> = files
            .iter()
            .map(|m| format!("{crate_sources}/{}", m.join("/")))
            .collect();
        panic!("a circle among the files: {}", shown.join(" → "));
    }
}

#[test]
fn no_circle_among_the_application_crates_files() {
    assert_no_circle("src", &[]);
}

#[test]
fn no_circle_among_the_runtimes_files() {
    assert_no_circle("runtime/src", &[]);
}

#[test]
fn no_circle_among_the_compilers_files() {
    assert_no_circle("codegen/src", &["front/lower", "ir"]);
}

/// Writes `text` to `file` below the temporary crate `root`.
fn write_source(root: &Path, file: &str, text: &str) {
    let path = root.join(file);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, text).unwrap();
}

/// The check sees a circle where there is one, through a re-export as the leg's errors were
/// (`leg.rs` returned `experiments::Error`, which wrapped what wraps the leg's), and none in
/// the same files once the error no longer wraps back.
#[test]
fn a_circle_through_a_reexport_is_found() {
    let root = super::support::scratch("file_circles_reexport");
    let write = |file: &str, text: &str| write_source(&root, file, text);
    write("lib.rs", "pub mod experiments;\npub mod sweep;\n");
    write(
        "experiments/mod.rs",
        "pub mod error;\npub mod leg;\npub use error::Error;\n",
    );
    write(
        "experiments/leg.rs",
        "use super::Error;\npub struct Leg;\npub fn open() -> Result<Leg, Error> { Ok(Leg) }\n",
    );
    write(
        "experiments/error.rs",
        "pub enum Error { Sweep(Box<crate::sweep::Error>) }\n",
    );
    write(
        "sweep.rs",
        "use crate::experiments;\npub enum Error { Model(experiments::Error) }\n",
    );
    let graph = uses_graph(&root);
    let found = circle(&graph).expect("the errors' circle");
    let names: Vec<String> = found.iter().map(|m| m.join("/")).collect();
    assert!(
        names.contains(&"experiments/error".to_string()) && names.contains(&"sweep".to_string()),
        "{names:?}"
    );
    // The leg's error no longer wrapped by what it wraps: no circle.
    write("experiments/error.rs", "pub enum Error { Io }\n");
    assert_eq!(circle(&uses_graph(&root)), None);
    // A re-export outside a folder's face is a use: back to a circle through it alone.
    write(
        "experiments/error.rs",
        "pub enum Error { Sweep(Box<crate::sweep::Error>) }\n",
    );
    write(
        "sweep.rs",
        "pub use crate::experiments::leg::Leg;\npub enum Error { Io }\n",
    );
    assert!(
        circle(&uses_graph(&root)).is_some(),
        "the re-export's circle"
    );
    std::fs::remove_dir_all(&root).unwrap();
}

/// Writes `files` as a temporary crate, checks that it has no circle, then writes `change`
/// over one of them and checks that it has one (`what`).
fn circle_only_after(name: &str, files: &[(&str, &str)], change: (&str, &str), what: &str) {
    let root = super::support::scratch(name);
    for (file, text) in files {
        write_source(&root, file, text);
    }
    assert_eq!(circle(&uses_graph(&root)), None, "before: {what}");
    write_source(&root, change.0, change.1);
    assert!(circle(&uses_graph(&root)).is_some(), "{what}");
    std::fs::remove_dir_all(&root).unwrap();
}

/// A lone name in a folder's `mod.rs` that matches one of its files (`match hinge` in
/// `ir/transform/mod.rs`) is a variable, not a use of the file; `hinge::twist()` is one.
#[test]
fn a_variable_named_like_a_child_module_is_not_a_use() {
    circle_only_after(
        "file_circles_lone_name",
        &[
            ("lib.rs", "pub mod transform;\n"),
            (
                "transform/hinge.rs",
                "use super::Axis;\npub fn twist() {}\n",
            ),
            (
                "transform/mod.rs",
                "pub mod hinge;\npub struct Axis;\npub fn axis(hinge: u8) -> u8 { hinge }\n",
            ),
        ],
        (
            "transform/mod.rs",
            "pub mod hinge;\npub struct Axis;\npub fn axis() { hinge::twist() }\n",
        ),
        "mod.rs ⇄ hinge.rs",
    );
}

/// A `use` inside a function is a use of what it names; a test-only method is not read.
#[test]
fn a_use_inside_a_function_counts_and_a_test_method_does_not() {
    circle_only_after(
        "file_circles_nested",
        &[
            ("lib.rs", "pub mod a;\npub mod b;\n"),
            ("a.rs", "pub struct A;\npub fn make() -> crate::b::B { crate::b::B }\n"),
            (
                "b.rs",
                "pub struct B;\nimpl B {\n    #[cfg(test)]\n    fn probe() -> crate::a::A { crate::a::A }\n}\n",
            ),
        ],
        ("b.rs", "pub struct B;\npub fn probe() { use crate::a::A; let _ = A; }\n"),
        "a.rs ⇄ b.rs",
    );
}

/// A module's face uses what it re-exports from its own files where it names it
/// (`pub use error::Error;` then `-> Error`), and a module imported under another name
/// (`use crate::experiments as exp;`) is followed through that name.
#[test]
fn a_faces_own_names_and_renamed_imports_are_followed() {
    circle_only_after(
        "file_circles_face",
        &[
            ("lib.rs", "pub mod experiments;\n"),
            (
                "experiments/mod.rs",
                "pub mod error;\npub use error::Error;\npub struct Kind;\npub fn f() -> Option<Error> { None }\n",
            ),
            ("experiments/error.rs", "pub struct Error;\n"),
        ],
        (
            "experiments/error.rs",
            "use super::Kind;\npub struct Error(pub Kind);\n",
        ),
        "mod.rs ⇄ error.rs",
    );
    circle_only_after(
        "file_circles_rename",
        &[
            ("lib.rs", "pub mod experiments;\npub mod top;\n"),
            ("experiments/mod.rs", "pub mod leg;\n"),
            ("experiments/leg.rs", "pub fn open() {}\n"),
            (
                "top.rs",
                "use crate::experiments as exp;\npub fn run() { exp::leg::open() }\n",
            ),
        ],
        (
            "experiments/leg.rs",
            "pub fn open() { crate::top::run() }\n",
        ),
        "top.rs ⇄ leg.rs",
    );
}
