//! The motion of a model's bodies over a run, for drawing it (`mech animate`).
//!
//! Consumes: a compiled model and a run as `mech simulate` writes it (a table with `t` and a
//! `q_<coordinate>` column per coordinate; parameters as set for the run). Produces:
//! [`Animation`], plain data: per body the positions in the Newtonian frame of the points
//! that show it (`ir::transform::skeleton`: origin, centre of mass, its points) at every
//! sample. Positions depend on `q` alone, so the speeds and inputs of the run are not read.

use mech_codegen::ir::transform::skeleton;
use mech_codegen::Compiled;
use mech_runtime::Model;

use crate::output::CsvTable;
use crate::tape_model::TapeModel;

/// One body's shown points over the run.
#[derive(Clone, Debug, PartialEq)]
pub struct AnimatedBody {
    pub name: String,
    /// What each point is (`arm origin`, `arm centre of mass`, `arm.tip`).
    pub labels: Vec<String>,
    /// `positions[sample][point]`, metres, in N.
    pub positions: Vec<Vec<[f64; 3]>>,
}

/// A run drawn as moving points.
#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    pub model: String,
    /// Sample times, seconds.
    pub times: Vec<f64>,
    pub bodies: Vec<AnimatedBody>,
}

/// Why a run cannot be animated.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(
        "the run has no column `{column}` (model `{model}`): animate the CSV that `mech simulate` \
         wrote for this model"
    )]
    MissingColumn { column: String, model: String },
    #[error("the run has no samples")]
    Empty,
}

/// The positions of every body's shown points at each sample of `run`. `values` sets the
/// model's parameters (SI, in parameter order) as they were for the run.
pub fn animate(compiled: &Compiled, values: &[f64], run: &CsvTable) -> Result<Animation, Error> {
    let mut ir = compiled.model.clone();
    let shape = skeleton::add_skeleton_outputs(&mut ir);
    let mut model = TapeModel::new(&Compiled::from_model(ir));
    for (i, &value) in values.iter().enumerate().take(model.nparams()) {
        model.set_param(i, value);
    }
    let missing = |column: &str| Error::MissingColumn {
        column: column.to_string(),
        model: compiled.model.name.clone(),
    };
    let time = run.column_index("t").ok_or_else(|| missing("t"))?;
    let coordinates: Vec<usize> = (0..model.nq())
        .map(|i| {
            let column = format!("q_{}", model.coordinate_name(i));
            run.column_index(&column).ok_or_else(|| missing(&column))
        })
        .collect::<Result<_, _>>()?;
    let times = run.columns[time].clone();
    if times.is_empty() {
        return Err(Error::Empty);
    }
    let outputs: Vec<Vec<usize>> = shape
        .bodies
        .iter()
        .map(|body| {
            body.points
                .iter()
                .map(|(_, output)| {
                    let x = format!("{output}.x");
                    model
                        .output_index(&x)
                        .expect("the skeleton's outputs are in the model")
                })
                .collect()
        })
        .collect();
    let mut bodies: Vec<AnimatedBody> = shape
        .bodies
        .iter()
        .map(|body| AnimatedBody {
            name: body.name.clone(),
            labels: body.points.iter().map(|(label, _)| label.clone()).collect(),
            positions: Vec::with_capacity(times.len()),
        })
        .collect();
    let (u, inputs) = (vec![0.0; model.nu()], vec![0.0; model.ninputs()]);
    let mut y = vec![0.0; model.noutputs()];
    for (sample, &t) in times.iter().enumerate() {
        let q: Vec<f64> = coordinates
            .iter()
            .map(|&c| run.columns[c][sample])
            .collect();
        model.outputs(t, &q, &u, &inputs, &mut y);
        for (body, indices) in bodies.iter_mut().zip(&outputs) {
            body.positions.push(
                indices
                    .iter()
                    .map(|&k| [y[k], y[k + 1], y[k + 2]])
                    .collect(),
            );
        }
    }
    Ok(Animation {
        model: compiled.model.name.clone(),
        times,
        bodies,
    })
}
