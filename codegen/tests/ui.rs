//! Golden diagnostics: every `tests/ui/<error_kind>.mech` must fail to load, and its rendered
//! errors must equal `tests/ui/<error_kind>.stderr`.
//!
//! Consumes: the `.mech` files in `codegen/tests/ui/` (paths shown relative to the crate root,
//! so the goldens do not depend on the machine).
//! Produces: one test per file, named after it, plus one that fails when a file and the
//! list in `tests_per_file!` differ (so a new file cannot go unchecked).
//! `MECH_BLESS=1 cargo test -p mech-codegen --test ui` rewrites the `.stderr` files instead.

#[macro_use]
#[path = "support/golden.rs"]
mod support;

use std::sync::Arc;

use mech_codegen::diag::SourceFile;
use mech_codegen::front;

/// Checks (or, with `MECH_BLESS=1`, rewrites) the golden file of `tests/ui/<stem>.mech`: what
/// `front::load` prints for it.
fn check(stem: &str) {
    support::check_failing_input(
        "tests/ui",
        stem,
        "mech",
        "(loaded without errors)\n",
        |shown, text| {
            front::load(Arc::new(SourceFile::new(shown, text)))
                .map(drop)
                .map_err(|errors| errors.to_string())
        },
    );
}

tests_per_file! {
    check:
    actuator_missing_voltage,
    add_mass_and_length,
    axis2_on_pin,
    axis_on_ball,
    axis_on_weld,
    ball_joint_coordinate_output,
    ball_u0_not_a_vector,
    bushing_to_itself,
    bushing_unknown_field,
    compound_q0_not_a_vector,
    constraint_not_linear,
    constraint_without_speed,
    contact_damping_unit,
    contact_missing_fields,
    contact_negative_friction,
    contact_to_itself,
    contact_unknown_field,
    contact_unknown_output,
    detached_cycle,
    disconnected_body,
    distance_of_a_number,
    division_by_zero,
    duplicate_field,
    energy_in_force,
    euler_starts_singular,
    euler_unknown_sequence,
    expected_rotation,
    expected_vector,
    exponent_not_constant,
    flexure_missing_frequency,
    flexure_nonpositive_dimension,
    flexure_on_slider,
    function_argument_dimension,
    inertia_four_entries,
    inertia_negative_moment,
    inertia_triangle,
    input_in_body_property,
    joint_to_itself,
    let_before_definition,
    loop_bad_component,
    loop_field_of_other_kind,
    loop_missing_axis,
    loop_zero_length,
    many_errors,
    missing_axis,
    missing_mass,
    negative_mass,
    nested_too_deeply,
    newtonian_child,
    no_bodies,
    non_constant_axis,
    non_integer_dimension,
    not_a_number,
    number_out_of_range,
    output_before_use,
    param_not_constant,
    planar_joint_coordinate_output,
    point_on_wrong_body,
    q0_on_quaternion_ball,
    redefinition,
    reserved_name,
    rolling_plane_on_a_body,
    rotation_on_pin,
    scalar_output_in_frame,
    speed_count,
    speed_not_linear,
    speed_without_joint_speed,
    speeds_dependent,
    spherical_joint_kind,
    spring_ends_meet,
    spring_missing_stiffness,
    spring_tension_unit,
    spring_to_itself,
    spring_unknown_field,
    spring_unknown_point,
    spring_wrong_unit,
    state_force_unit,
    state_in_let,
    state_of_a_ball,
    syntax_expected_expression,
    syntax_missing_semicolon,
    syntax_unclosed_block,
    twist_along_loop_axis,
    two_parent_joints,
    universal_parallel_axes,
    unknown_body,
    unknown_field,
    unknown_frame,
    unknown_function,
    unknown_joint_kind,
    unknown_loop_kind,
    unknown_material,
    unknown_name,
    unknown_point,
    unknown_unit,
    unterminated_comment,
    v0_on_pin,
    wrong_component_count,
    wrong_dimension,
    zero_axis,
}

#[test]
fn every_ui_file_has_a_test_and_a_golden_file() {
    support::assert_lists_every_input_and_golden(LISTED, "tests/ui", "mech", "codegen/tests/ui.rs");
}
