//! `mech sweep`: the sampler's statistics, a sweep checked sample by sample against a closed
//! form, Spearman's ρ against a hand computation, determinism across thread counts, and the
//! study file's errors naming key and line.

use std::path::Path;
use std::process::Command;

use mech::sweep::sample::{values, Dist, Source};
use mech::sweep::stats::{ranking, spearman, summary};
use mech::sweep::study;

fn draws(dist: Dist, n: usize, seed: u64) -> Vec<f64> {
    let names = ["p".to_string()];
    let sources = [Source::Draw(dist)];
    (0..n)
        .map(|i| values(&names, &sources, seed, i).unwrap()[0])
        .collect()
}

/// 20,000 normal draws: the mean within 4 standard errors, the sd within 4 of its standard
/// error (σ/√(2n)), the fraction within ±1σ within 4 binomial standard errors of 68.27 %.
#[test]
fn normal_draws_have_their_mean_and_sd() {
    let n = 20_000;
    let (mean, sd) = (3.0, 0.5);
    let x = draws(Dist::Normal { mean, sd }, n, 11);
    let s = summary(&x);
    let se = sd / (n as f64).sqrt();
    assert!((s.mean - mean).abs() < 4.0 * se, "mean {}", s.mean);
    assert!(
        (s.sd - sd).abs() < 4.0 * sd / (2.0 * n as f64).sqrt(),
        "sd {}",
        s.sd
    );
    let inside = x.iter().filter(|v| (*v - mean).abs() < sd).count() as f64 / n as f64;
    let p = 0.682_689_492_137_085_9;
    assert!(
        (inside - p).abs() < 4.0 * (p * (1.0 - p) / n as f64).sqrt(),
        "{inside}"
    );
}

/// Kolmogorov–Smirnov on 20,000 uniform draws: the largest distance between the empirical and
/// the exact CDF under 1.95/√n (the 0.1 % critical value).
#[test]
fn uniform_draws_pass_kolmogorov_smirnov() {
    let n = 20_000;
    let (low, high) = (-2.0, 5.0);
    let mut x = draws(Dist::Uniform { low, high }, n, 3);
    x.sort_by(f64::total_cmp);
    let d = x
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let f = (v - low) / (high - low);
            (f - i as f64 / n as f64)
                .abs()
                .max(((i + 1) as f64 / n as f64 - f).abs())
        })
        .fold(0.0, f64::max);
    assert!(d < 1.95 / (n as f64).sqrt(), "KS distance {d}");
    assert!(x.iter().all(|v| (low..high).contains(v)));
}

/// A normal truncated to [μ, μ + 10σ] is a half-normal: every draw inside, its mean
/// μ + σ√(2/π) and its sd σ√(1 − 2/π), each within 4 standard errors.
#[test]
fn truncated_normal_draws_stay_inside_their_bounds() {
    let n = 20_000;
    let (mean, sd) = (1.0, 0.2);
    let dist = Dist::TruncatedNormal {
        mean,
        sd,
        low: mean,
        high: mean + 10.0 * sd,
    };
    let x = draws(dist, n, 5);
    assert!(x.iter().all(|v| (mean..=mean + 10.0 * sd).contains(v)));
    let s = summary(&x);
    let half_sd = sd * (1.0 - 2.0 / std::f64::consts::PI).sqrt();
    let expected = mean + sd * (2.0 / std::f64::consts::PI).sqrt();
    assert!(
        (s.mean - expected).abs() < 4.0 * half_sd / (n as f64).sqrt(),
        "{}",
        s.mean
    );
    assert!(
        (s.sd - half_sd).abs() < 4.0 * half_sd / (2.0 * n as f64).sqrt(),
        "{}",
        s.sd
    );
}

/// A sample's draws depend on the seed and its index only: another seed or index differs,
/// the same ones repeat.
#[test]
fn draws_are_a_function_of_seed_and_index() {
    let names = ["a".to_string(), "b".to_string()];
    let sources = [
        Source::Draw(Dist::Normal { mean: 0.0, sd: 1.0 }),
        Source::Draw(Dist::Uniform {
            low: 0.0,
            high: 1.0,
        }),
    ];
    let at = |seed, i| values(&names, &sources, seed, i).unwrap();
    assert_eq!(at(1, 17), at(1, 17));
    assert_ne!(at(1, 17), at(1, 18));
    assert_ne!(at(1, 17), at(2, 17));
}

/// Spearman's ρ by hand: x = 1..5, y = (5, 6, 7, 8, 7) ranks (1, 2, 3.5, 5, 3.5); with the
/// ranks' deviations (−2, −1, 0, 1, 2) and (−2, −1, 0.5, 2, 0.5): ρ = 8/√(10 · 9.5).
#[test]
fn spearman_matches_a_hand_computation() {
    let x = [1.0, 2.0, 3.0, 4.0, 5.0];
    let y = [5.0, 6.0, 7.0, 8.0, 7.0];
    let rho = spearman(&x, &y);
    assert!((rho - 8.0 / 95.0_f64.sqrt()).abs() < 1e-15, "{rho}");
    // A monotone decreasing transform is −1; NaN pairs are left out.
    let z = [9.0, 4.0, f64::NAN, 1.0, 0.5];
    assert_eq!(spearman(&x, &z), -1.0);
    // The ranking orders by |ρ|: z (−1) before y (0.82), and a constant column last.
    let constant = vec![2.0; 5];
    let order = ranking(&[y.to_vec(), constant, z.to_vec()], &[x.to_vec()]);
    let parameters: Vec<usize> = order[0].iter().map(|c| c.parameter).collect();
    assert_eq!(parameters, [2, 0, 1]);
    assert!(order[0][2].rho.is_nan());
}

fn study_text(body: &str) -> String {
    format!(
        "model = \"{}/models/two_mass_chain.mech\"\nseed = 4\n{body}",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn prepare(body: &str) -> Result<mech::sweep::Study, String> {
    let text = study_text(body);
    study::parse(&text)
        .and_then(|file| mech::sweep::prepare(&file, &text))
        .map_err(|e| e.to_string())
}

/// The two-mass chain's natural frequencies under sampled `k1` and `m2`, each sample against
/// the roots of m1 m2 ω⁴ − (m1 k2 + m2 (k1 + k2)) ω² + k1 k2 = 0.
#[test]
fn natural_frequencies_match_the_closed_form_sample_by_sample() {
    let study = prepare(
        "samples = 60\noutputs = [\"natural_frequency.1\", \"natural_frequency.2\"]\n\
         [[parameter]]\nname = \"k1\"\ndistribution = \"normal\"\nmean = \"300 N/m\"\nsd = \"40 N/m\"\n\
         [[parameter]]\nname = \"m2\"\nrelative = true\ndistribution = \"uniform\"\nlow = 0.5\nhigh = 2\n",
    )
    .unwrap();
    let table = study.run_all(2, &|| {}).unwrap();
    assert_eq!(table.rows.len(), 60);
    assert_eq!(table.failed(), 0);
    let (m1, k2) = (2.0, 120.0);
    for row in &table.rows {
        let (k1, m2) = (row.parameters[0], 0.5 * row.parameters[1]);
        let (a, b, c) = (m1 * m2, m1 * k2 + m2 * (k1 + k2), k1 * k2);
        let root = (b * b - 4.0 * a * c).sqrt();
        let hz = |w2: f64| w2.sqrt() / std::f64::consts::TAU;
        let expected = [hz((b - root) / (2.0 * a)), hz((b + root) / (2.0 * a))];
        for (got, want) in row.outputs.iter().zip(expected) {
            assert!(
                ((got - want) / want).abs() < 1e-9,
                "sample {}: {got} Hz against {want} Hz",
                row.index
            );
        }
    }
}

/// A grid: the cartesian product in order (last parameter fastest), `lo..hi:n` evenly.
#[test]
fn a_grid_is_the_cartesian_product() {
    let study = prepare(
        "outputs = [\"natural_frequency.1\"]\n\
         [[parameter]]\nname = \"k1\"\nvalues = [\"100 N/m\", \"200 N/m\"]\n\
         [[parameter]]\nname = \"k2\"\nrange = \"10 N/m .. 30 N/m : 3\"\n",
    )
    .unwrap();
    assert_eq!(study.samples, 6);
    let table = study.run_all(1, &|| {}).unwrap();
    let points: Vec<Vec<f64>> = table.rows.iter().map(|r| r.parameters.clone()).collect();
    let expected = [
        [100.0, 10.0],
        [100.0, 20.0],
        [100.0, 30.0],
        [200.0, 10.0],
        [200.0, 20.0],
        [200.0, 30.0],
    ];
    assert_eq!(points, expected.map(|p| p.to_vec()));
}

/// The error `prepare` gives for a study it refuses.
fn refused(body: &str) -> String {
    prepare(body).err().expect("an error")
}

/// Errors name the key and its line: a unit of another dimension than the parameter's, an
/// unknown key, an unknown parameter, a grid mixed with draws, too many samples.
#[test]
fn study_errors_name_the_key_and_line() {
    let normal = "[[parameter]]\nname = \"k1\"\ndistribution = \"normal\"\n";
    let outputs = "samples = 10\noutputs = [\"natural_frequency.1\"]\n";
    let e = refused(&format!(
        "{outputs}{normal}mean = \"300 mm\"\nsd = \"1 N/m\"\n"
    ));
    assert_eq!(
        e,
        "line 8: key `parameter[1].mean`: `300 mm` has unit m, but parameter `k1` is in N/m"
    );
    let e = refused(&format!("{outputs}{normal}mean = 300\nsd = \"1 N/m\"\n"));
    assert!(
        e.starts_with("line 8: key `parameter[1].mean`: `300.0` has no unit"),
        "{e}"
    );
    let e = refused(&format!(
        "{outputs}{normal}mean = \"1 N/m\"\nsd = \"1 N/m\"\nspread = 2\n"
    ));
    assert!(e.starts_with("line 10: unknown key `spread`"), "{e}");
    let e = refused(&format!(
        "{outputs}[[parameter]]\nname = \"k9\"\nvalues = [\"1 N/m\"]\n"
    ));
    assert!(
        e.starts_with("line 6: key `parameter[1].name`: model"),
        "{e}"
    );
    assert!(e.contains("has no parameter `k9`"), "{e}");
    let e = refused("samples = 2000000\noutputs = [\"natural_frequency.1\"]\n[[parameter]]\nname = \"k1\"\ndistribution = \"uniform\"\nlow = \"1 N/m\"\nhigh = \"2 N/m\"\n");
    assert_eq!(
        e,
        "line 3: key `samples`: more than 1000000 samples; split the study"
    );
    let e = refused(&format!(
        "{outputs}{normal}mean = \"1 N/m\"\nsd = \"1 N/m\"\n[[parameter]]\nname = \"k2\"\nvalues = [\"1 N/m\"]\n"
    ));
    assert!(e.contains("a study is a grid"), "{e}");
    let big = |unit: &str| format!("range = \"1 {unit} .. 2 {unit} : 1000\"\n");
    let e = refused(&format!(
        "outputs = [\"natural_frequency.1\"]\n[[parameter]]\nname = \"k1\"\n{}\
         [[parameter]]\nname = \"k2\"\n{}[[parameter]]\nname = \"m1\"\n{}",
        big("N/m"),
        big("N/m"),
        big("kg")
    ));
    assert_eq!(
        e,
        "line 11: key `parameter[3]`: more than 1000000 samples; split the study"
    );
    let twice = "[[parameter]]\nname = \"k1\"\nvalues = [\"1 N/m\"]\n";
    let e = refused(&format!(
        "outputs = [\"natural_frequency.1\"]\n{twice}{twice}"
    ));
    assert_eq!(
        e,
        "line 8: key `parameter[2].name`: `k1` is already parameter[1]; give each parameter once"
    );
    let e = refused("samples = 3\noutputs = [\"stroke\"]\nparameter = []\n");
    assert!(
        e.starts_with("line 4: key `outputs`: unknown output `stroke`"),
        "{e}"
    );
}

fn run_cli(study: &Path, out: &Path, threads: &str) -> Vec<u8> {
    let status = Command::new(env!("CARGO_BIN_EXE_mech"))
        .args([
            "sweep",
            study.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .args(["--threads", threads])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    std::fs::read(out.join("samples.csv")).unwrap()
}

/// The same seed on one thread and on two: the same CSV, byte for byte (HAMR-VI's force test
/// under stiffness tolerances).
#[test]
fn one_and_two_threads_write_the_same_csv() {
    let dir = std::env::temp_dir().join(format!("mech-sweep-threads-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let study = dir.join("study.toml");
    std::fs::write(
        &study,
        "model = \"models/hamr_vi.mech\"\nseed = 9\nsamples = 12\nvoltage = \"225 V\"\n\
         outputs = [\"free_stroke.lift\", \"blocked_force.swing\"]\n\
         [[parameter]]\nname = \"k_l3\"\nrelative = true\ndistribution = \"normal\"\nmean = 1.0\nsd = 0.1\n\
         [[parameter]]\nname = \"k_s1\"\nrelative = true\ndistribution = \"truncated_normal\"\n\
         mean = 1.0\nsd = 0.2\nlow = 0.8\nhigh = 1.1\n",
    )
    .unwrap();
    let one = run_cli(&study, &dir.join("one"), "1");
    let two = run_cli(&study, &dir.join("two"), "2");
    assert_eq!(String::from_utf8_lossy(&one), String::from_utf8_lossy(&two));
    assert_eq!(one.iter().filter(|&&b| b == b'\n').count(), 13);
    let _ = std::fs::remove_dir_all(&dir);
}
