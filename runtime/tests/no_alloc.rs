//! Stepping a model never allocates: all working storage is allocated up front.

use mech_runtime::{
    AdaptiveOptions, Dopri5, ExpRosenbrock, Model, ModelOde, Reduced, Rk4, Rosenbrock, Signal,
    Stepper,
};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

mod common;
use common::model_metadata;

/// Counts allocations made by the current thread while `COUNTING` is set.
struct CountingAlloc;

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.with(Cell::get) {
            COUNT.with(|c| c.set(c.get() + 1));
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: CountingAlloc = CountingAlloc;

/// Allocations made by `f` on this thread.
fn allocations(f: impl FnOnce()) -> usize {
    COUNT.with(|c| c.set(0));
    COUNTING.with(|c| c.set(true));
    f();
    COUNTING.with(|c| c.set(false));
    COUNT.with(Cell::get)
}

/// Two coupled pendulum-like coordinates with a full, configuration-dependent, SPD or
/// indefinite mass matrix, so that both the Cholesky and the LU paths run.
struct Coupled {
    indefinite: bool,
}

impl Model for Coupled {
    model_metadata! {
        name: "coupled",
        coordinates: ["q", "q"],
        initial_q: [0.0, 0.0],
        inputs: ["torque"],
        outputs: [],
        params: [],
    }
    fn mass_matrix(&self, _t: f64, q: &[f64], _inputs: &[f64], out: &mut [f64]) {
        let c = 0.5 * (q[0] - q[1]).cos();
        let d = if self.indefinite { -1.0 } else { 1.0 };
        out.copy_from_slice(&[2.0, c, c, d]);
    }
    fn forcing(&self, _t: f64, q: &[f64], u: &[f64], inputs: &[f64], out: &mut [f64]) {
        out[0] = -q[0].sin() - 0.1 * u[0] + inputs[0];
        out[1] = -q[1].sin() - 0.1 * u[1];
    }
    fn outputs(&self, _t: f64, _q: &[f64], _u: &[f64], _inputs: &[f64], _out: &mut [f64]) {}
}

#[test]
fn stepping_does_not_allocate() {
    // The counter works.
    assert_eq!(allocations(|| drop(std::hint::black_box(vec![1.0]))), 1);
    let signals = [Signal::table(vec![0.0, 1.0, 2.0], vec![0.0, 1.0, -1.0]).unwrap()];
    for indefinite in [false, true] {
        let model = Coupled { indefinite };
        let x0 = [0.5, -0.2, 0.0, 0.0];

        let ode = ModelOde::new(&model, &signals).unwrap();
        let mut dopri = Dopri5::new(ode, 0.0, &x0, 3.0, AdaptiveOptions::default()).unwrap();
        let mut out = [0.0; 4];
        let n = allocations(|| {
            while !dopri.is_finished() {
                dopri.step().unwrap();
                let t = 0.5 * (dopri.t_prev() + dopri.t());
                dopri.interpolate(t, &mut out).unwrap();
                dopri.state_mut()[2] *= 1.0;
            }
        });
        assert!(dopri.stats().accepted_steps > 10);
        assert_eq!(n, 0, "DOPRI5 allocated (indefinite M: {indefinite})");

        let ode = ModelOde::new(&model, &signals).unwrap();
        let mut rk4 = Rk4::new(ode, 0.0, &x0, 3.0, 0.01).unwrap();
        let n = allocations(|| {
            while !rk4.is_finished() {
                rk4.step().unwrap();
            }
        });
        assert_eq!(n, 0, "RK4 allocated (indefinite M: {indefinite})");
    }

    // The stiff methods, on the full and on the reduced form (all coordinates independent).
    let model = Coupled { indefinite: false };
    let x0 = [0.5, -0.2, 0.0, 0.0];
    let opts = AdaptiveOptions::rosenbrock();
    let mut out = [0.0; 4];
    let mut stepped = |stepper: &mut dyn Stepper| {
        let n = allocations(|| {
            while !stepper.is_finished() {
                stepper.step().unwrap();
                let t = 0.5 * (stepper.t_prev() + stepper.t());
                stepper.interpolate(t, &mut out).unwrap();
            }
        });
        assert!(stepper.stats().accepted_steps > 10);
        n
    };
    let ode = ModelOde::new(&model, &signals).unwrap();
    let n = stepped(&mut Rosenbrock::new(ode, 0.0, &x0, 3.0, opts).unwrap());
    assert_eq!(n, 0, "Rosenbrock allocated");
    let ode = ModelOde::new(&model, &signals).unwrap();
    let n = stepped(&mut ExpRosenbrock::new(ode, 0.0, &x0, 3.0, opts).unwrap());
    assert_eq!(n, 0, "ExpRosenbrock allocated");
    let reduced = Reduced::new(&model, &signals, 0.0, &x0[..2], &[0, 1], 1e-12).unwrap();
    let n = stepped(&mut ExpRosenbrock::new(reduced, 0.0, &x0, 3.0, opts).unwrap());
    assert_eq!(n, 0, "ExpRosenbrock on the reduced dynamics allocated");
}
