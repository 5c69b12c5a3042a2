//! `.mech` source of the N-link 3D chain of `../shared/peers/chain_model.py`.
//!
//! Shared by the library and `build.rs` (included there with `#[path]`), so the models the
//! build script compiles and the ones the benchmark derives at run time are the same text.

/// Chain sizes of the benchmark.
pub const SIZES: [usize; 6] = [1, 2, 4, 8, 16, 32];

/// Sizes of the floating chain (a `free` joint carrying N links) of the benchmark.
pub const FLOATING_SIZES: [usize; 4] = [4, 8, 16, 32];

/// Names of the nine inertial parameters of a link, in the order of `chain_model.py`.
const LINK_PARAMS: [&str; 9] = ["m", "l", "d", "Ixx", "Iyy", "Izz", "Ixy", "Iyz", "Izx"];

/// The N-link chain written exactly like `models/chain4.mech` (same parameters, axes
/// alternating x/y, `q0 = 0.5 rad`); `chain_source(4)` is that file byte for byte.
pub fn chain_source(n: usize) -> String {
    chain_text(n, false, false)
}

/// The same chain on a floating base (issue 15): a body like the links, `base`, on a `free`
/// joint `float` (its origin at the world's origin at rest), with link 1 pinned `l` below
/// the base's origin about the base's x, the axes alternating x/y as before. Coordinates
/// `q1 … qN`, `float.e0 … e3`, `float.x/y/z` (world); speeds `q1 … qN`, `float.wx/wy/wz`,
/// `float.vx/vy/vz` (both in the base's frame). `tests/peers/pinocchio_free_chain.py`
/// builds the same model in Pinocchio and MuJoCo.
pub fn floating_chain_source(n: usize) -> String {
    chain_text(n, false, true)
}

/// The same chain with its own nine parameters per link (`m1`, `l1`, ..., `Izx{n}`) and
/// `g`, as the SymPy peer keeps them: the like-for-like model for operation counts, where
/// shared parameters would let identical terms of different links merge.
pub fn chain_source_per_link(n: usize) -> String {
    chain_text(n, true, false)
}

fn chain_text(n: usize, per_link: bool, floating: bool) -> String {
    let name = match (per_link, floating) {
        (true, _) => format!("chain{n}_per_link"),
        (false, true) => format!("free_chain{n}"),
        (false, false) => format!("chain{n}"),
    };
    let mut s = String::new();
    s.push_str(&format!(
        "/// The N-link 3D chain of ../shared/peers/chain_model.py with N = {n}: identical links\n\
         /// hanging along -z, joint k about the parent's x (k odd) or y (k even), full inertia tensors.\n"
    ));
    if per_link {
        s.push_str("/// Every link has its own parameters, as in the SymPy peer.\n");
    }
    if floating {
        s.push_str("/// On a floating base: a body like the links on a `free` joint, link 1 pinned to it.\n");
    }
    s.push_str(&format!("model {name};\n\n"));
    let units = [
        "kg", "m", "m", "kg*m^2", "kg*m^2", "kg*m^2", "kg*m^2", "kg*m^2", "kg*m^2",
    ];
    let values = [
        "1.0", "1.0", "0.5", "0.0845", "0.0855", "0.0125", "0.001", "0.002", "0.003",
    ];
    let links: Vec<String> = if per_link {
        (1..=n).map(|k| k.to_string()).collect()
    } else {
        vec![String::new()]
    };
    for suffix in &links {
        for ((param, unit), value) in LINK_PARAMS.iter().zip(units).zip(values) {
            s.push_str(&format!("param {param}{suffix} = {value} {unit};\n"));
        }
    }
    s.push_str("param g = 9.81 m/s^2;\n\ngravity = [0, 0, -g];\n");
    let suffix = |k: usize| {
        if per_link {
            k.to_string()
        } else {
            String::new()
        }
    };
    let body_name = |k: usize| {
        if k == 0 {
            "base".to_string()
        } else {
            format!("link{k}")
        }
    };
    let first = if floating { 0 } else { 1 };
    for k in first..=n {
        let p = suffix(k);
        s.push_str(&format!(
            "\nbody {} {{\n    mass = m{p};\n    com = [0, 0, -d{p}];\n    \
             inertia = [Ixx{p}, Iyy{p}, Izz{p}, Ixy{p}, Iyz{p}, Izx{p}];\n}}\n",
            body_name(k)
        ));
    }
    if floating {
        s.push_str("\njoint float = free(newtonian, base);\n");
    }
    for k in 1..=n {
        let parent = if k == 1 && !floating {
            "newtonian".to_string()
        } else {
            body_name(k - 1)
        };
        let axis = if k % 2 == 1 { "x" } else { "y" };
        s.push_str(&format!(
            "\njoint q{k} = pin({parent}, link{k}) {{\n    axis = {axis};\n"
        ));
        if k > 1 || floating {
            s.push_str(&format!(
                "    parent_point = [0, 0, -l{}];\n",
                suffix(k - 1)
            ));
        }
        s.push_str("    q0 = 0.5 rad;\n}\n");
    }
    s.push_str("\noutput ke = kinetic_energy;\noutput pe = potential_energy;\n");
    s
}
