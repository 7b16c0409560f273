//! `pkm simulate-measurements` and `pkm calibrate`: identification of a machine's
//! geometric parameters (seed 001) from a measurement campaign, real or simulated
//! (`pkm::analysis::identification`).

use clap::Args;
use std::path::Path;
use std::path::PathBuf;

use anyhow::{Context, Result};

mod fit;
mod simulate;
pub use fit::{calibrate_run, plot_svgs};
pub use simulate::simulate_run;

#[derive(Args)]
pub struct SimulateArgs {
    /// Machine file (TOML, type = "hexapod"): the nominal machine.
    pub machine: PathBuf,
    /// Half-width of the uniform deviations of every joint coordinate and zero length of
    /// the true machine (mm) [default: 1, times the campaign's scale].
    #[arg(long)]
    pub deviation: Option<f64>,
    /// Standard deviation of the measured point coordinates (mm).
    #[arg(long, default_value_t = 0.005)]
    pub point_noise: f64,
    /// Standard deviation of the strut length readings (mm).
    #[arg(long, default_value_t = 0.001)]
    pub length_noise: f64,
    /// Number of states for identification.
    #[arg(long, default_value_t = 50)]
    pub states: usize,
    /// Further states on the same true machine, written to validation.csv.
    #[arg(long, default_value_t = 0)]
    pub holdout: usize,
    /// `random` (poses around home within every limit) or `one-strut` (seed 001: the
    /// zero state, then one more strut changed per state).
    #[arg(long, default_value = "random")]
    pub design: String,
    /// Half-width of the random poses' translations (mm) [default: 100, times the
    /// campaign's scale].
    #[arg(long)]
    pub translation: Option<f64>,
    /// Half-width of the random poses' angles (deg) [default: 10, halved while fewer
    /// than a fifth of the random poses are within the limits].
    #[arg(long)]
    pub rotation: Option<f64>,
    /// Largest condition number of a random state, as a multiple of the home pose's:
    /// states nearer a singularity are drawn again (`inf`: none refused).
    #[arg(long, default_value_t = pkm::identify::simulate::CONDITION_RATIO)]
    pub condition_ratio: f64,
    /// Strut change per state of the one-strut design (mm) [default: 40, times the
    /// campaign's scale].
    #[arg(long)]
    pub step: Option<f64>,
    /// Size of the fixture (mm): the circumradius of a strut machine's triangle, the
    /// spacing of a pentapod's two points on its tool axis [default: 200, times the
    /// campaign's scale].
    ///
    /// The campaign's scale is 1 unless fewer than a fifth of the random poses within
    /// +-100 mm and +-10 deg of home are within the machine's limits and the condition
    /// ratio (a machine much smaller than 100 mm: then it halves until they are) or the
    /// struts average more than 1 m at home (then it doubles while the span stays
    /// within a fifth of them and a fifth of the poses within the limits), so the
    /// defaults fit a micro-positioner and a hexapod of metres as well as a machine
    /// tool.
    #[arg(long)]
    pub fixture_radius: Option<f64>,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Print truth.json (the true parameters and poses) and the files written to stdout.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct CalibrateArgs {
    /// Machine file (TOML, type = "hexapod"): the nominal machine, start of the fit.
    pub machine: PathBuf,
    /// Measurement file (CSV, see `pkm simulate-measurements --help`).
    #[arg(long)]
    pub measurements: PathBuf,
    /// `pose` (full pose per state from >= 3 fixture points) or `points` (points only,
    /// e.g. one laser-tracker target).
    #[arg(long, default_value = "pose")]
    pub model: String,
    /// Parameters held at their nominal values (names as in report.json, e.g. A1.z).
    #[arg(long)]
    pub fix: Option<String>,
    /// Write the seed 001 procedure's solution (first seven states, six systems of seven
    /// equations) to identified.toml instead of Levenberg-Marquardt's.
    #[arg(long)]
    pub seed_procedure: bool,
    /// States not used for identification: point errors of the nominal and identified
    /// models.
    #[arg(long)]
    pub validation: Option<PathBuf>,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Print report.json to stdout.
    #[arg(long)]
    pub json: bool,
}

/// The text of the file `path`.
fn read(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))
}
