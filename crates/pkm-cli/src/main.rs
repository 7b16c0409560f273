//! `pkm`: kinematics and accuracy of parallel, hybrid and serial machine tools.

mod commands;
mod io;
mod poses;
mod report;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use pkm::Convention;

/// Exit code for a pose or actuator set the machine cannot reach (limits, no solution).
pub const EXIT_UNREACHABLE: u8 = 3;

#[derive(Parser)]
#[command(
    name = "pkm",
    version,
    about = "Kinematics and accuracy of parallel, hybrid and serial machine tools and robots",
    long_about = "Kinematics and accuracy of parallel, hybrid and serial machine tools and robots.\n\n\
        Units: millimetres and degrees in files, on the command line and in outputs.\n\
        Exit codes: 0 success, 1 bad input or error, 2 bad command line, 3 a pose that is\n\
        unreachable (a limit is violated) or forward kinematics that found no pose.",
    after_help = "Examples:\n  \
        pkm report                                    # HTML report of the bundled seed-000 tripod\n  \
        pkm check examples/machines/tripod-seed000.toml\n  \
        pkm ik examples/machines/tripod-seed000.toml --pose=-20,45.54,-286.25,15,0,0 --json\n  \
        pkm fk examples/machines/tripod-seed000.toml --actuators 208.2,208.2,208.2"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Inverse kinematics: actuator values and joint positions for a pose, limits checked.
    #[command(after_help = "Examples:\n  \
        pkm ik examples/machines/tripod-seed000.toml --pose=-20,45.54,-286.25,15,0,0\n  \
        pkm ik examples/machines/tripod-seed000.toml --pose 0,0,-290 --json\n  \
        pkm ik examples/machines/tripod-seed000.toml --pose=10,0,-280,0,5,0 --rotation zyx\n  \
        pkm ik MACHINE.toml --input poses.csv --output actuators.csv\n\n\
        Spatial machines take X,Y,Z (mm) and optionally three angles (deg) in the chosen\n\
        convention; without angles the machine's own orientation is used (the home\n\
        orientation of a translational tripod, the one its centre leg sets for a Tricept).\n\
        A CSV input has a header row naming the same values (X,Y,Z[,A,B,C]).")]
    Ik(IkArgs),
    /// Forward kinematics: the pose for actuator values, from a starting pose.
    #[command(after_help = "Examples:\n  \
        pkm fk examples/machines/tripod-seed000.toml --actuators 208.2,208.2,208.2\n  \
        pkm fk examples/machines/tripod-seed000.toml --actuators 215.35,189.24,224.44 --from=-20,45.54,-286.25,15,0,0 --json\n  \
        pkm fk MACHINE.toml --input lengths.csv --output poses.csv\n\n\
        Coordinates the actuators do not drive (the held orientation of a translational\n\
        tripod) are taken from --from (default: the home pose). In a CSV batch each row\n\
        starts from the previous row's solution, as a machine moving through the states.")]
    Fk(FkArgs),
    /// Run a tool path (G-code, or a point-to-point move) through the machine: actuator
    /// position, velocity and acceleration over time, the same path on a serial machine,
    /// limits along the path.
    #[command(after_help = "Examples:\n  \
        pkm motion examples/machines/tripod-seed000.toml --gcode examples/paths/seed000-arc.ngc --feed 10000 --points 101 --out arc\n  \
        pkm motion examples/machines/tripod-seed000.toml --from 0,0,-290 --to 40,20,-300 --feed 3000 --profile scurve --out p2p\n  \
        pkm motion MACHINE.toml --from POSE --to POSE --duration 1 --profile trapezoid --accel-time 0.1 --out DIR\n\n\
        Writes DIR/actuators.csv (t, line, pose coordinates, then per actuator position,\n\
        velocity, acceleration), DIR/summary.json and DIR/actuators.svg, DIR/serial.svg.\n\
        A program starts at --from when given, else at the machine's home pose. Moves stop\n\
        exactly at each segment end (no blending). Exit code 3 when a limit is violated.")]
    Motion(MotionArgs),
    /// Map the workspace: reachable points, the limit that binds elsewhere, and the
    /// Jacobian's conditioning, on a grid (rayon, all cores).
    #[command(after_help = "Examples:\n  \
        pkm workspace examples/machines/hexapod-linuxcnc.toml --step 20 --out ws\n  \
        pkm workspace examples/machines/hexapod-linuxcnc.toml --orientation 0,10,0 --bounds=-400,400,-400,400,300,800 --step 10 --out ws\n  \
        pkm workspace examples/machines/hexapod-linuxcnc.toml --tilt 15 --step 25 --out total   # reachable at every tilt <= 15 deg\n  \
        pkm workspace examples/machines/hexapod-linuxcnc.toml --at 0,0,550 --out tilt          # orientation workspace at a point\n\n\
        Writes DIR/summary.json (volume_mm3, bounding_box, reachable_fraction, condition\n\
        statistics, points per binding limit), DIR/points.csv, DIR/points.ply and slice heat maps.")]
    Workspace(WorkspaceArgs),
    /// Accuracy of any machine (seed 003's model): the tool-pose error of given
    /// deviations, the sensitivity to every geometric parameter, the error budget of
    /// the tolerances, a Monte Carlo of them and an error map.
    #[command(after_help = "Examples:\n  \
        pkm errors examples/machines/mc300.toml --actuators 100,-50,-80,30,45 --out err\n  \
        pkm errors examples/machines/mc300.toml --actuators 100,-50,-80,30,45 --monte-carlo 100000 --json --out err\n  \
        pkm errors examples/machines/mc300.toml --deviations devs.toml --out err   # devs.toml: \"delta_x(1 slide)\" = 0.01\n  \
        pkm errors examples/machines/mc300.toml --tolerances tight.toml --map X,Y --out map\n  \
        pkm errors examples/machines/hexapod-seed001.toml --pose 0,0,550,5,0,0 --joint-tolerance 0.01 --length-tolerance 0.005 --monte-carlo 100000 --out hex\n  \
        pkm errors examples/machines/p3rp-seed004.toml --link-tolerance 0.02 --angle-tolerance 0.01 --map z,theta --out head\n\n\
        Tolerances: --tolerances FILE, else the per-kind flags when any is given, else the\n\
        machine file's [[tolerance]] entries, else +-0.01 mm on lengths and +-0.01 mrad on angles.\n\
        Writes DIR/errors.json (pose, parameters' sensitivities, tolerances, budget,\n\
        monte_carlo, error_map), DIR/budget.svg, DIR/monte-carlo.svg, DIR/error-map.csv/svg.\n\
        Units: mm; deg for angular parameters and rotary axes.")]
    Errors(ErrorsArgs),
    /// Simulate an identification campaign (seed 001): a true machine drawn around the
    /// file's, states measured with a triangular fixture, noise on points and readings.
    #[command(after_help = "Examples:\n  \
        pkm simulate-measurements examples/machines/hexapod-seed001.toml --deviation 1 --point-noise 0.005 --length-noise 0.001 --states 50 --holdout 20 --seed 1 --out sim\n  \
        pkm simulate-measurements examples/machines/hexapod-seed001.toml --design one-strut --states 7 --point-noise 0 --length-noise 0 --out seven\n\n\
        Writes DIR/measurements.csv (the format `pkm calibrate` reads: `# fixture P1 = x, y, z`\n\
        lines, then state,dL1..dL6,P1_x,...), DIR/validation.csv with --holdout, DIR/true.toml\n\
        (the true machine, a machine file) and DIR/truth.json.")]
    SimulateMeasurements(SimulateArgs),
    /// Identify a machine's geometric parameters (hexapod: the 42 of seed 001) from
    /// measurements, with standard errors and the identifiability analysis.
    #[command(after_help = "Examples:\n  \
        pkm calibrate examples/machines/hexapod-seed001.toml --measurements sim/measurements.csv --validation sim/validation.csv --out cal\n  \
        pkm calibrate MACHINE.toml --measurements tracker.csv --model points --out cal     # laser tracker: points only\n  \
        pkm calibrate MACHINE.toml --measurements m.csv --fix A1.z,A2.z --out cal           # hold parameters\n\n\
        Writes DIR/identified.toml (a machine file every command accepts), DIR/report.json\n\
        (parameters with standard errors, residual RMS before/after, singular values,\n\
        condition number, unidentifiable combinations, validation), DIR/residuals.svg and\n\
        DIR/singular-values.svg. A rank-deficient problem fails, naming the combination.")]
    Calibrate(CalibrateArgs),
    /// Validate a machine file and summarise it.
    #[command(after_help = "Example:\n  pkm check examples/machines/tripod-seed000.toml --json")]
    Check(CheckArgs),
    /// Write the HTML report (machine drawing, kinematic checks, analyses) to DIR/index.html.
    #[command(after_help = "Examples:\n  \
        pkm report                       # bundled seed-000 tripod, writes pkm-report/index.html\n  \
        pkm report examples/machines/tripod-seed000.toml --out my-report")]
    Report(ReportArgs),
}

#[derive(Args)]
pub struct PoseOptions {
    /// Convention of the angles in poses: rpy (A,B,C: R = Rz(C) Ry(B) Rx(A), default),
    /// zyx, zyz, krylov (seed 001), rotvec.
    #[arg(long, default_value = "rpy", value_parser = parse_convention)]
    pub rotation: Convention,
    /// Print machine-readable JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

fn parse_convention(s: &str) -> Result<Convention, String> {
    s.parse::<Convention>().map_err(|e| e.to_string())
}

#[derive(Args)]
pub struct IkArgs {
    /// Machine file (TOML).
    pub machine: PathBuf,
    /// Pose: X,Y,Z[,A,B,C] (mm, deg) for spatial machines, the machine's own coordinates otherwise.
    #[arg(
        long,
        allow_hyphen_values = true,
        required_unless_present = "input",
        conflicts_with = "input"
    )]
    pub pose: Option<String>,
    /// CSV of many poses (header row naming the values).
    #[arg(long, requires = "output")]
    pub input: Option<PathBuf>,
    /// CSV to write the batch results to.
    #[arg(long, requires = "input")]
    pub output: Option<PathBuf>,
    /// Six-axis robots: every inverse solution found (postures: shoulder, elbow, wrist),
    /// nearest to home first, each with its limit status.
    #[arg(long, conflicts_with = "input")]
    pub all_solutions: bool,
    #[command(flatten)]
    pub opts: PoseOptions,
}

#[derive(Args)]
pub struct FkArgs {
    /// Machine file (TOML).
    pub machine: PathBuf,
    /// Actuator values v1,v2,... (mm for linear, deg for revolute drives).
    #[arg(
        long,
        allow_hyphen_values = true,
        required_unless_present = "input",
        conflicts_with = "input"
    )]
    pub actuators: Option<String>,
    /// Starting pose (same form as `pkm ik --pose`); default: the home pose.
    #[arg(long, allow_hyphen_values = true)]
    pub from: Option<String>,
    /// Also search for other assembly modes: solve from this many starting poses spread
    /// around home (and mirrored through the base plane) and list every distinct pose.
    #[arg(long, conflicts_with = "input")]
    pub assembly_modes: Option<usize>,
    /// CSV of many actuator sets (header row naming the actuators).
    #[arg(long, requires = "output")]
    pub input: Option<PathBuf>,
    /// CSV to write the batch results to.
    #[arg(long, requires = "input")]
    pub output: Option<PathBuf>,
    #[command(flatten)]
    pub opts: PoseOptions,
}

#[derive(Args)]
pub struct MotionArgs {
    /// Machine file (TOML).
    pub machine: PathBuf,
    /// G-code program.
    #[arg(long, conflicts_with = "to")]
    pub gcode: Option<PathBuf>,
    /// Start pose (as `pkm ik --pose`); default: the home pose.
    #[arg(long, allow_hyphen_values = true)]
    pub from: Option<String>,
    /// End pose of a point-to-point move.
    #[arg(long, allow_hyphen_values = true)]
    pub to: Option<String>,
    /// Feed (mm/min), replacing the program's F words.
    #[arg(long)]
    pub feed: Option<f64>,
    /// Velocity profile of each move.
    #[arg(long, value_enum, default_value = "constant")]
    pub profile: ProfileArg,
    /// Path acceleration for trapezoid and scurve (mm/s^2).
    #[arg(long, default_value_t = 1000.0)]
    pub accel: f64,
    /// Path jerk for scurve (mm/s^3).
    #[arg(long, default_value_t = 20000.0)]
    pub jerk: f64,
    /// Rapid (G0) rate (mm/min); default: the machine file's `[motion] rapid`, else 10000.
    #[arg(long)]
    pub rapid: Option<f64>,
    /// Duration of a point-to-point move (s), instead of --feed.
    #[arg(long)]
    pub duration: Option<f64>,
    /// Acceleration (and deceleration) time of a timed trapezoid (s).
    #[arg(long)]
    pub accel_time: Option<f64>,
    /// Sampling rate (Hz); default 1000.
    #[arg(long, conflicts_with = "points")]
    pub rate: Option<f64>,
    /// Points per move instead of a rate (seed 000: 101).
    #[arg(long)]
    pub points: Option<usize>,
    /// Convention of angles in --from/--to.
    #[arg(long, default_value = "rpy", value_parser = parse_convention)]
    pub rotation: Convention,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Skip actuators.csv (summary and plots only), for very long programs.
    #[arg(long)]
    pub summary_only: bool,
    /// Print summary.json to stdout.
    #[arg(long)]
    pub json: bool,
}

/// Velocity profile names on the command line.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum ProfileArg {
    /// Constant feed.
    Constant,
    /// Trapezoidal velocity.
    Trapezoid,
    /// Jerk-limited S-curve.
    Scurve,
}

impl From<ProfileArg> for pkm::motion::program::ProfileKind {
    fn from(p: ProfileArg) -> Self {
        match p {
            ProfileArg::Constant => Self::Constant,
            ProfileArg::Trapezoid => Self::Trapezoid,
            ProfileArg::Scurve => Self::Scurve,
        }
    }
}

#[derive(Args)]
pub struct WorkspaceArgs {
    /// Machine file (TOML).
    pub machine: PathBuf,
    /// Constant orientation A,B,C (deg) of the map; default: the home orientation.
    #[arg(long, allow_hyphen_values = true)]
    pub orientation: Option<String>,
    /// Grid bounds min,max per axis (X,Y,Z in mm for spatial machines).
    #[arg(long, allow_hyphen_values = true)]
    pub bounds: Option<String>,
    /// Grid step (mm, or deg for angle axes); default: 1/40 of each range.
    #[arg(long)]
    pub step: Option<f64>,
    /// Total orientation workspace: reachable only if reachable at tilts of this many
    /// degrees in 8 directions as well as untilted.
    #[arg(long)]
    pub tilt: Option<f64>,
    /// Orientation workspace at a point X,Y,Z: the largest reachable tilt per direction.
    #[arg(long, allow_hyphen_values = true)]
    pub at: Option<String>,
    /// Largest tilt searched with --at (deg).
    #[arg(long, default_value_t = 60.0)]
    pub max_tilt: f64,
    /// Convention of --orientation.
    #[arg(long, default_value = "rpy", value_parser = parse_convention)]
    pub rotation: Convention,
    /// Performance atlas: largest rate of every pose coordinate (mm/s, deg/s), one value
    /// per coordinate; writes atlas.csv and maps of the actuator positions and of the
    /// actuator velocities and accelerations these capacities need.
    #[arg(long, allow_hyphen_values = true)]
    pub atlas_velocity: Option<String>,
    /// Performance atlas: largest acceleration of every pose coordinate (mm/s^2, deg/s^2).
    #[arg(long, allow_hyphen_values = true)]
    pub atlas_acceleration: Option<String>,
    /// Forward workspace: forward kinematics over a grid of the actuator strokes
    /// (machines with at most 3 actuators); writes forward.csv and maps of the pose.
    #[arg(long)]
    pub forward: bool,
    /// Step of the --forward grid (mm or deg); default 1/40 of each stroke.
    #[arg(long)]
    pub forward_step: Option<f64>,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Print summary.json to stdout.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct SimulateArgs {
    /// Machine file (TOML, type = "hexapod"): the nominal machine.
    pub machine: PathBuf,
    /// Half-width of the uniform deviations of every joint coordinate and zero length of
    /// the true machine (mm).
    #[arg(long, default_value_t = 1.0)]
    pub deviation: f64,
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
    /// Half-width of the random poses' translations (mm).
    #[arg(long, default_value_t = 100.0)]
    pub translation: f64,
    /// Half-width of the random poses' angles (deg).
    #[arg(long, default_value_t = 10.0)]
    pub rotation: f64,
    /// Strut change per state of the one-strut design (mm).
    #[arg(long, default_value_t = 40.0)]
    pub step: f64,
    /// Circumradius of the triangular fixture (mm).
    #[arg(long, default_value_t = 200.0)]
    pub fixture_radius: f64,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
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

#[derive(Args)]
pub struct ErrorsArgs {
    /// Machine file (TOML or URDF): any machine type.
    pub machine: PathBuf,
    /// Pose (as `pkm ik --pose`); default: home.
    #[arg(long, allow_hyphen_values = true)]
    pub pose: Option<String>,
    /// Actuator values instead of a pose (mm, deg; forward kinematics from home).
    #[arg(long, allow_hyphen_values = true)]
    pub actuators: Option<String>,
    /// Convention of the angles in --pose.
    #[arg(long, default_value = "rpy", value_parser = parse_convention)]
    pub rotation: Convention,
    /// Tolerance of every joint-centre coordinate (mm).
    #[arg(long)]
    pub joint_tolerance: Option<f64>,
    /// Tolerance of every zero length and linear drive positioning (mm).
    #[arg(long)]
    pub length_tolerance: Option<f64>,
    /// Tolerance of every link dimension and linear link deviation (mm).
    #[arg(long)]
    pub link_tolerance: Option<f64>,
    /// Tolerance of every angular parameter, revolute drives included (deg).
    #[arg(long)]
    pub angle_tolerance: Option<f64>,
    /// With the per-kind tolerances: `uniform` (in +-tolerance) or `normal`
    /// (tolerance = 3 sigma).
    #[arg(long, default_value = "uniform")]
    pub distribution: String,
    /// TOML file of deviation values by parameter name (mm; deg for angles): their
    /// exact tool-pose error.
    #[arg(long)]
    pub deviations: Option<PathBuf>,
    /// Tolerances file (`[[tolerance]]` entries with `deviation`, `value`, optional
    /// `distribution`) instead of the machine file's or the per-kind ones.
    #[arg(long)]
    pub tolerances: Option<PathBuf>,
    /// Monte Carlo of the tolerances with this many machines.
    #[arg(long)]
    pub monte_carlo: Option<usize>,
    /// Seed of the Monte Carlo.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Error map over two pose coordinates (names, e.g. X,Y; a joint-space machine's
    /// joints over their travel), the others at the pose: RSS and worst case per point.
    #[arg(long)]
    pub map: Option<String>,
    /// Points per axis of the error map.
    #[arg(long, default_value_t = 41)]
    pub map_points: usize,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Print errors.json to stdout.
    #[arg(long)]
    pub json: bool,
}

#[derive(clap::Args, Debug)]
pub struct CheckArgs {
    /// Machine file (TOML).
    pub machine: PathBuf,
    /// Print machine-readable JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct ReportArgs {
    /// Machine file (TOML); default: the bundled seed-000 tripod.
    pub machine: Option<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "pkm-report")]
    pub out: PathBuf,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let res = match cli.command {
        Command::Ik(a) => commands::ik::run(&a),
        Command::Fk(a) => commands::fk::run(&a),
        Command::Check(a) => commands::check::run(&a),
        Command::Motion(a) => commands::motion::run(&a),
        Command::Workspace(a) => commands::workspace::run(&a),
        Command::Errors(a) => commands::errors::run(&a),
        Command::SimulateMeasurements(a) => commands::calibrate::simulate_run(&a),
        Command::Calibrate(a) => commands::calibrate::calibrate_run(&a),
        Command::Report(a) => report::run(&a),
    };
    match res {
        Ok(code) => ExitCode::from(code),
        Err(e) => {
            let chain: Vec<String> = e.chain().map(|c| c.to_string()).collect();
            eprintln!("error: {}", chain.join(": "));
            let unreachable = matches!(
                e.downcast_ref::<pkm::Error>(),
                Some(
                    pkm::Error::Unreachable { .. }
                        | pkm::Error::NotAttainable { .. }
                        | pkm::Error::NotConverged { .. }
                        | pkm::Error::Singular { .. }
                )
            );
            ExitCode::from(if unreachable { EXIT_UNREACHABLE } else { 1 })
        }
    }
}
