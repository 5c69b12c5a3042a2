//! Front-end tests: parse + lower smoke tests, units, the frame tree of a joint, and errors.
//!
//! Consumes: small model texts written inline.
//! Produces: assertions on the IR and on diagnostic codes/messages (the exact rendering is
//! covered by the golden files in `codegen/tests/ui/`).

use std::sync::Arc;

use super::{load, parse, units};
use crate::diag::{Errors, SourceFile};
use crate::ir::{Dimension, Expr, JointKind, Model, Motion, OutputKind};
use crate::sym::Number;

fn model(text: &str) -> Model {
    match load(Arc::new(SourceFile::new("test.mech", text))) {
        Ok(model) => model,
        Err(errors) => panic!("{errors}"),
    }
}

fn errors(text: &str) -> Errors {
    match load(Arc::new(SourceFile::new("test.mech", text))) {
        Ok(_) => panic!("expected errors for:\n{text}"),
        Err(errors) => errors,
    }
}

fn codes(text: &str) -> Vec<&'static str> {
    errors(text).diagnostics.iter().map(|d| d.code).collect()
}

/// `text` fails with the one error `code`.
fn check_code(text: &str, code: &str) {
    assert_eq!(codes(text), [code], "{text}");
}

fn rational(n: i64, d: i64) -> Expr {
    Expr::Number(Number::Rational(n, d))
}

const PENDULUM: &str = "
/// A pendulum.
model pendulum;
param m = 10 g;
param l = 25 mm;
param g = 9.81 m/s^2;
gravity = [0, -g, 0];
body arm {
    mass = m;
    com = [0, -l/2, 0];
    point tip = [0, -l, 0];
}
joint hinge = pin(newtonian, arm) { axis = z; q0 = 30 deg; }
output angle = hinge.q;
output tip = position(arm.tip);
";

#[test]
fn loads_a_pendulum() {
    let model = model(PENDULUM);
    assert_eq!(model.name, "pendulum");
    assert_eq!(model.docs, vec!["A pendulum."]);
    assert_eq!(model.params.len(), 3);
    let (_, l) = model.params.iter().nth(1).unwrap();
    assert_eq!(
        (l.name.as_str(), l.value, l.dimension),
        ("l", 0.025, Dimension::LENGTH)
    );
    let names: Vec<&str> = model.frames.iter().map(|(_, f)| f.name.as_str()).collect();
    assert_eq!(names, ["newtonian", "hinge", "arm"]);
    let points: Vec<&str> = model.points.iter().map(|(_, p)| p.name.as_str()).collect();
    assert_eq!(points, ["arm", "arm.com", "arm.tip"]);
    let (_, q) = model.coordinates.iter().next().unwrap();
    assert!((q.initial - std::f64::consts::PI / 6.0).abs() < 1e-15);
    assert_eq!(model.joints.len(), 1);
    assert!(model.gravity.is_some());
    assert!(matches!(model.outputs[0].kind, OutputKind::Coordinate(_)));
    assert!(matches!(model.outputs[1].kind, OutputKind::Position { .. }));
}

#[test]
fn model_name_defaults_to_the_file_stem() {
    let file = SourceFile::new(
        "models/four-bar.mech",
        "body b { mass = 1 g; } joint j = weld(newtonian, b);",
    );
    let model = load(Arc::new(file)).unwrap();
    assert_eq!(model.name, "four_bar");
}

#[test]
fn parse_keeps_docs_and_spans() {
    let file = SourceFile::new(
        "t.mech",
        "//! Model docs.\n/// The mass.\nparam m = 10 g;\n",
    );
    let ast = parse(&file).unwrap();
    assert_eq!(ast.docs, vec!["Model docs."]);
    let super::ast::Item::Param(param) = &ast.items[0] else {
        panic!()
    };
    assert_eq!(param.docs, vec!["The mass."]);
    assert_eq!(
        &file.text[param.name.span.start as usize..param.name.span.end as usize],
        "m"
    );
}

#[test]
fn pin_with_child_point_and_child_frame_builds_the_documented_frames() {
    let model = model(
        "body arm { mass = 1 g; frame f = rotate(x, 90 deg) * rotate(z, 2 rad); }
         newtonian { frame tilted = rotate(y, 1 rad) at [1 m, 0, 0]; point p = [0, 2 mm, 0]; }
         joint j = pin(newtonian, arm) {
             axis = [0, 3, 4]; parent_point = newtonian.p; child_point = [0, 5 mm, 0];
             parent_frame = newtonian.tilted; child_frame = arm.f;
         }",
    );
    let frames: Vec<_> = model.frames.iter().map(|(_, f)| f).collect();
    let names: Vec<&str> = frames.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "newtonian",
            "newtonian.tilted",
            "j",
            "j.child",
            "arm",
            "arm.f"
        ]
    );
    let joint = frames[2];
    assert_eq!(joint.parent, Some(Model::NEWTONIAN));
    assert_eq!(joint.origin, [Expr::zero(), rational(1, 500), Expr::zero()]);
    assert_eq!(joint.orientation.len(), 1);
    let Motion::Revolute { axis, .. } = &joint.motion else {
        panic!("{:?}", joint.motion)
    };
    assert_eq!(axis, &[Expr::zero(), rational(3, 5), rational(4, 5)]);
    let child = frames[3];
    assert_eq!(child.motion, Motion::Fixed);
    let angles: Vec<&Expr> = child.orientation.iter().map(|r| &r.angle).collect();
    assert_eq!(
        angles,
        [
            &Expr::Number(Number::int(-2)),
            &Expr::Number(Number::Float(-std::f64::consts::FRAC_PI_2))
        ]
    );
    assert_eq!(
        child.orientation[0].axis,
        [Expr::zero(), Expr::zero(), Expr::one()]
    );
    let arm = frames[4];
    assert_eq!(arm.parent.map(|h| h.index()), Some(3));
    assert_eq!(arm.origin, [Expr::zero(), rational(-1, 200), Expr::zero()]);
    assert_eq!(frames[5].parent.map(|h| h.index()), Some(4));
    assert_eq!(model.joints.iter().next().unwrap().1.parent, None);
}

#[test]
fn frames_are_appended_parents_first_whatever_the_declaration_order() {
    let model = model(
        "joint elbow = pin(upper, fore) { axis = z; }
         body fore { mass = 1 g; }
         joint shoulder = pin(newtonian, upper) { axis = z; }
         body upper { mass = 1 g; }
         joint slide = slider(upper, cart) { axis = x; q0 = 2 mm; }
         body cart { mass = 1 g; }",
    );
    for (handle, frame) in model.frames.iter() {
        if let Some(parent) = frame.parent {
            assert!(parent < handle, "{} before its parent", frame.name);
        }
    }
    let names: Vec<&str> = model
        .coordinates
        .iter()
        .map(|(_, c)| c.name.as_str())
        .collect();
    assert_eq!(names, ["shoulder", "elbow", "slide"]);
    let (_, slide) = model.coordinates.iter().nth(2).unwrap();
    assert_eq!((slide.dimension, slide.initial), (Dimension::LENGTH, 0.002));
    let bodies: Vec<&str> = model.bodies.iter().map(|(_, b)| b.name.as_str()).collect();
    assert_eq!(bodies, ["fore", "upper", "cart"]);
    let kinds: Vec<JointKind> = model.joints.iter().map(|(_, j)| j.kind).collect();
    assert_eq!(kinds, [JointKind::Pin, JointKind::Pin, JointKind::Slider]);
}

#[test]
fn springs_dampers_forces_and_lets() {
    let model = model(
        "param k = 2 uN*m/rad; param c = 1 N*m*s/rad; let k2 = 2 * k; input f = 0 mN;
         body b { mass = 1 g; inertia = [1, 2, 3, 0, 0, 0] * 1e-9 kg*m^2; point p = [1 mm, 0, 0]; }
         joint j = pin(newtonian, b) { axis = z; stiffness = k2; rest = 10 deg; damping = c; }
         force push at b.p = [f * sin(2 * pi * t / 1 s), 0, 0];
         torque tq on b = [0, 0, f * 1 m] in b;
         output e = f * 2;",
    );
    assert_eq!(model.loads.len(), 4);
    assert_eq!(
        model.inputs.iter().next().unwrap().1.dimension,
        Dimension::FORCE
    );
}

#[test]
fn exponents_may_be_rational() {
    let model = model(
        "param k = 4 N/m; param m = 1 g;
         let w = (k / m)^0.5;
         body b { mass = m; }
         joint j = slider(newtonian, b) { axis = x; }
         output w = w * 1 s;",
    );
    let OutputKind::Expr(Expr::Mul(w, _)) = &model.outputs[0].kind else {
        panic!("{:?}", model.outputs[0].kind)
    };
    assert!(matches!(**w, Expr::Pow(_, Number::Rational(1, 2))));
}

// ---------------------------------------------------------------------------------------------
// Units
// ---------------------------------------------------------------------------------------------

#[test]
fn units_are_exact_where_possible() {
    assert_eq!(
        units::lookup("mm").unwrap().scale,
        Number::Rational(1, 1000)
    );
    assert_eq!(units::lookup("kg").unwrap().scale, Number::ONE);
    assert_eq!(
        units::lookup("µm").unwrap().scale,
        Number::Rational(1, 1_000_000)
    );
    assert_eq!(
        units::lookup("GPa").unwrap().scale,
        Number::int(1_000_000_000)
    );
    assert_eq!(
        units::lookup("kHz").unwrap().dimension,
        Dimension {
            time: -1,
            ..Dimension::NONE
        }
    );
    assert!(matches!(
        units::lookup("deg").unwrap().scale,
        Number::Float(_)
    ));
    assert!(units::lookup("mdeg").is_none());
    assert!(units::lookup("x").is_none());
}

#[test]
fn parse_quantity_gives_si_values() {
    assert_eq!(units::parse_quantity("10 mN"), Ok((0.01, Dimension::FORCE)));
    assert_eq!(units::parse_quantity("2.5"), Ok((2.5, Dimension::NONE)));
    assert_eq!(
        units::parse_quantity("-1e-3 kg*m^2"),
        Ok((-1e-3, Dimension::INERTIA))
    );
    assert_eq!(
        units::parse_quantity("0 uN*m/rad"),
        Ok((0.0, Dimension::TORQUE))
    );
    assert_eq!(
        units::parse_quantity("3 N/m"),
        Ok((
            3.0,
            Dimension {
                mass: 1,
                time: -2,
                ..Dimension::NONE
            }
        ))
    );
    let (deg, dim) = units::parse_quantity("30 deg").unwrap();
    assert!((deg - std::f64::consts::PI / 6.0).abs() < 1e-15 && dim == Dimension::NONE);
    assert_eq!(
        units::parse_quantity("9.81 m/s^2").unwrap().1,
        Dimension::ACCELERATION
    );
    assert_eq!(
        units::parse_quantity("1 V").unwrap().1,
        Dimension {
            mass: 1,
            length: 2,
            time: -3,
            current: -1
        }
    );
    let unknown = units::parse_quantity("2 furlongs").unwrap_err();
    assert_eq!(
        unknown,
        units::QuantityError::UnknownUnit {
            name: "furlongs".into()
        }
    );
    assert!(unknown.to_string().contains("furlongs"));
    assert!(units::parse_quantity("1e999").is_err());
    assert!(units::parse_quantity("").is_err());
}

#[test]
fn five_millimetres_is_one_two_hundredth_of_a_metre() {
    let param = model("param l = 5 mm; body b { mass = 1 g; } joint j = weld(newtonian, b);");
    assert_eq!(param.params.iter().next().unwrap().1.value, 0.005);
    let with_com =
        model("body b { mass = 1 g; com = [5 mm, 0, 0]; } joint j = weld(newtonian, b);");
    assert_eq!(
        with_com.bodies.iter().next().unwrap().1.center_of_mass[0],
        rational(1, 200)
    );
}

// ---------------------------------------------------------------------------------------------
// Errors
// ---------------------------------------------------------------------------------------------

#[test]
fn adding_a_length_to_a_mass_is_an_error() {
    let errors = errors("param m = 1 kg; param l = 1 m; let x = m + l;");
    assert_eq!(errors.diagnostics.len(), 1);
    let diagnostic = &errors.diagnostics[0];
    assert_eq!(
        (diagnostic.code, diagnostic.message.as_str()),
        ("E0301", "cannot add kg and m")
    );
    assert_eq!(diagnostic.labels.len(), 2);
}

#[test]
fn dimension_errors() {
    check_code(
        "body b { mass = 1 m; } joint j = weld(newtonian, b);",
        "E0302",
    );
    check_code("param a = 1 m; let s = sin(a);", "E0303");
    check_code("param a = 1 m; let s = a^0.5;", "E0304");
    check_code("param a = 1 m; let s = a^(1 s);", "E0305");
    check_code("param a = 2; let s = a^a;", "E0401");
    check_code("param a = 1 m; let s = 1 m^60 * 1 m^60;", "E0304");
    check_code("gravity = [0, -9.81 m/s, 0];", "E0302");
}

#[test]
fn every_error_of_the_phase_is_reported() {
    let codes = codes("param a = 1 q; param b = 2 m + 1 s; let c = nope; body x { mass = 1 g; }");
    assert_eq!(codes, ["E0206", "E0301", "E0204", "E0407"]);
}

/// A param or input whose value has an error is reported there alone, not again as a
/// dimension error wherever it is used (a unit typo once gave a dozen errors).
#[test]
fn a_value_with_an_error_is_reported_once() {
    let text = "
        param l = 40 mn;
        input push = 1 mNN;
        body b { mass = 1 g; com = [0, -l/2, 0]; inertia = [l^2 * 1 g, l^2 * 1 g, l^2 * 1 g]; }
        joint j = pin(newtonian, b) { axis = z; parent_point = [0, -l, 0]; }
        force f at b = [push, 0, 0] in newtonian;
        output half = l / 2;
    ";
    assert_eq!(codes(text), ["E0206", "E0206"], "{}", errors(text));
    check_code(
        "param l = 40 mn; let twice = 2 * l; output o = twice + 1 m;",
        "E0206",
    );
}

#[test]
fn structure_errors() {
    check_code(
        "body a { mass = 1 g; } joint j = pin(newtonian, a) { axis = [0, 0, 0]; }",
        "E0405",
    );
    check_code(
        "body a { mass = 1 g; } joint j = pin(newtonian, a);",
        "E0402",
    );
    check_code(
        "body a { mass = 1 g; } joint j = weld(newtonian, a) { axis = z; }",
        "E0403",
    );
    check_code(
        "body a { mass = 1 g; inertia = [1, 2, 3, 4]; } joint j = weld(newtonian, a);",
        "E0404",
    );
    check_code("body a { } joint j = weld(newtonian, a);", "E0402");
    check_code("body a { mass = 1 g; } joint j = weld(a, a);", "E0408");
    check_code(
        "body a { mass = 1 g; } joint j = weld(a, newtonian);",
        "E0409",
    );
    let cycle = "body a { mass = 1 g; } body b { mass = 1 g; } joint j1 = weld(a, b); joint j2 = weld(b, a);";
    check_code(cycle, "E0410");
    let loop_ = "body a { mass = 1 g; } body b { mass = 1 g; }
        joint j1 = weld(newtonian, a); joint j2 = weld(a, b); joint j3 = weld(newtonian, b);";
    check_code(loop_, "E0406");
}

#[test]
fn name_errors_suggest_candidates() {
    let errors = errors("body forearm { mass = 1 g; } joint j = weld(newtonian, forearm2);");
    let d = &errors.diagnostics[0];
    assert_eq!(d.code, "E0201");
    assert_eq!(d.help.as_deref(), Some("did you mean `forearm`?"));
    check_code("param m = 1 g; param m = 2 g;", "E0210");
    check_code("param t = 1 s;", "E0212");
    check_code("let a = b; let b = 1;", "E0214");
}

#[test]
fn syntax_errors_name_what_was_expected() {
    let incomplete = errors("param l = 2 * ;");
    let d = &incomplete.diagnostics[0];
    assert_eq!(d.code, "E0101");
    assert!(
        d.message.starts_with("expected an expression"),
        "{}",
        d.message
    );
    let missing = errors("param l = 2\nparam m = 1;");
    assert_eq!(
        missing.diagnostics[0].message,
        "expected `;` or an operator, found `param`"
    );
    assert_eq!(missing.diagnostics[0].labels[0].span.start, 11);
}

#[test]
fn deep_nesting_is_an_error_not_a_crash() {
    let deep = format!("param a = {}1{};", "(".repeat(10_000), ")".repeat(10_000));
    check_code(&deep, "E0103");
    let long = format!("param a = 1{};", " + 1".repeat(10_000));
    check_code(&long, "E0103");
    // Rejected before pest holds its tree: counted in the text (the `;` ends the count).
    let huge = format!(
        "param b = 1;\n  param a = 1{};\nparam c = 1{};",
        " + 1".repeat(100_001),
        " - 1".repeat(99_999)
    );
    let too_large = errors(&huge);
    assert_eq!(too_large.diagnostics.len(), 1);
    assert_eq!(too_large.diagnostics[0].message, "expression is too large");
    assert_eq!(
        too_large.diagnostics[0].labels[0].span.start, 15,
        "at `param a`"
    );
    let below = format!("param a = 1;\nparam b = 1{};", " - 1".repeat(99_999));
    assert_eq!(
        errors(&below).diagnostics[0].message,
        "expression is nested too deeply"
    );
    let minus = format!("param a = {}1;", "-".repeat(100_000));
    check_code(&minus, "E0505");
    let mut lets = String::from("param a = 1;\nlet x0 = a;\n");
    for i in 1..40 {
        lets.push_str(&format!("let x{i} = x{} * x{};\n", i - 1, i - 1));
    }
    check_code(&lets, "E0103");
}

#[test]
fn huge_numbers_and_exponents_do_not_overflow() {
    check_code("param a = 1e999;", "E0102");
    check_code("param a = 1 m^99999999999999999999;", "E0304");
    check_code("param a = 2^99999999999;", "E0413");
    check_code("param a = 1 / 0;", "E0413");
    // Read without errors of their own (the file only lacks bodies).
    check_code("param a = 1.5e-2147483648;", "E0505");
    check_code(
        "param a = 99999999999999999999999999999999999999999 mm;",
        "E0505",
    );
}

/// `constraint`: both forms lower (a velocity's components, a scalar row), and what is not
/// `A(q) u = 0` is refused at its span.
#[test]
fn velocity_constraints() {
    let base = "param r = 5 mm;\nbody cart { mass = 1 g; }\nbody wheel { mass = 1 g; }\n\
                joint x = slider(newtonian, cart) { axis = x; }\n\
                joint spin = pin(cart, wheel) { axis = z; }\n";
    let with = |line: &str| format!("{base}{line}\n");
    let lowered = model(&with(
        "constraint a = velocity(cart, wheel) in cart { components = [x, y]; }\n\
         constraint b = cos(spin.q) * x.u - r * spin.u;",
    ));
    assert_eq!(lowered.velocity_constraints.len(), 2);
    assert!(matches!(
        &lowered.velocity_constraints[0].kind,
        crate::ir::VelocityKind::PointVelocity { components, .. } if components == &[0, 1]
    ));
    for (line, code) in [
        ("constraint c = x.u * spin.u;", "E0420"),
        ("constraint c = sin(spin.u * 1 s);", "E0420"),
        ("constraint c = x.u / spin.u;", "E0420"),
        ("constraint c = x.u^2;", "E0420"),
        ("constraint c = x.u + x.q / 1 s;", "E0421"),
        ("constraint c = x.q;", "E0421"),
        ("constraint c = t * x.u;", "E0401"),
        ("constraint c = x.u in cart;", "E0403"),
        ("constraint c = x.u { components = [x]; }", "E0403"),
        ("constraint c = velocity(cart) { axis = x; }", "E0209"),
        ("constraint c = velocity(cart, nowhere);", "E0201"),
        ("constraint x = velocity(cart);", "E0210"),
    ] {
        check_code(&with(line), code);
    }
}
