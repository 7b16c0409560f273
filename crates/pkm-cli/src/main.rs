//! `pkm`: kinematics and accuracy of parallel, hybrid and serial machine tools.

mod columnar;
mod commands;
mod fixed;
mod io;
mod out;
mod poses;
mod progress;
mod report;

use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use commands::calibrate::{CalibrateArgs, SimulateArgs};
use commands::check::CheckArgs;
use commands::dynamics::DynamicsArgs;
use commands::errors::ErrorsArgs;
use commands::fk::FkArgs;
use commands::ik::IkArgs;
use commands::motion::MotionArgs;
use commands::statics::StaticsArgs;
use commands::workspace::WorkspaceArgs;
use pkm::Convention;
use report::ReportArgs;

/// Exit code for a pose or actuator set the machine cannot reach (limits, no solution).
pub const EXIT_UNREACHABLE: u8 = 3;

#[derive(Parser)]
#[command(
    name = "pkm",
    version,
    about = "Kinematics and accuracy of parallel, hybrid and serial machine tools and robots",
    long_about = "Kinematics and accuracy of parallel, hybrid and serial machine tools and robots.\n\n\
        Units: millimetres and degrees in files, on the command line and in outputs.\n\
        Exit codes: 0 success, 1 bad input or error, 2 bad command line (a malformed\n\
        option, or a pose or actuator list of the wrong length or magnitude), 3 a pose that\n\
        is unreachable (a limit is violated) or forward kinematics that found no pose, 4 a\n\
        report written without the sections that could not be computed.\n\
        Output to a pipe that closes (pkm ... | head) ends pkm quietly.\n\n\
        Environment: PKM_SIMD=scalar|avx2|avx512 lowers the vector instructions the\n\
        kernels use below the widest this CPU has (never above it).",
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
        pkm ik MACHINE.toml --input poses.csv --output actuators.csv\n  \
        pkm ik ROBOT.toml --input path.csv --output joints.csv --continuous   # rows of a path\n\n\
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
        pkm motion examples/machines/tripod-seed000.toml --gcode examples/paths/seed000-arc.ngc --from 32,-32,-290 --feed 10000 --points 101 --out arc\n  \
        pkm motion examples/machines/tripod-seed000.toml --from 0,0,-290 --to 40,20,-300 --feed 3000 --profile scurve --out p2p\n  \
        pkm motion MACHINE.toml --from POSE --to POSE --duration 1 --profile trapezoid --accel-time 0.1 --out DIR\n  \
        pkm motion examples/machines/mc300.toml --gcode tests/fixtures/linuxcnc/xyzbc-trt/boat-xyzbc.ngc --accuracy --out DIR\n  \
        pkm motion examples/machines/tripod-seed000.toml --gcode examples/paths/seed000-arc.ngc --from 32,-32,-290 --format parquet --out arc   # for pandas, polars\n\n\
        Writes DIR/actuators.csv (t, line, pose coordinates, then per actuator position,\n\
        velocity, acceleration; DIR/actuators.parquet with --format parquet), DIR/summary.json\n\
        and DIR/actuators.svg, DIR/serial.svg;\n\
        with --accuracy DIR/accuracy.csv (per G-code line) and DIR/accuracy.svg.\n\
        A program starts at --from when given, else at the machine's home pose. Moves stop\n\
        exactly at each segment end (no blending). Exit code 3 when a limit is violated.")]
    Motion(Box<MotionArgs>),
    /// Statics and stiffness at one pose: the actuator forces that hold a wrench on the
    /// tool, the 6 x 6 stiffness at the tool (with the load-dependent term) and the
    /// tool's deflection.
    #[command(after_help = "Examples:\n  \
        pkm statics examples/machines/hexapod-linuxcnc.toml --wrench 0,0,-1000\n  \
        pkm statics examples/machines/hexapod-linuxcnc.toml --pose 50,0,550,0,5,0 --wrench 200,0,-1000,0,0,10 --json\n\n\
        The wrench is the load on the tool in the base frame: force (N) at the tool tip,\n\
        moment (N m). Each strut, slide or joint needs `stiffness` in the machine file\n\
        (N/mm; N mm/rad for a revolute joint) for the stiffness and deflection; the\n\
        actuator forces need none. Passive joints and links are taken as rigid.")]
    Statics(StaticsArgs),
    /// Inverse dynamics of a serial machine or robot: the joint torques and forces for
    /// joint positions, rates and accelerations, with gravity and a load on the tool.
    #[command(after_help = "Examples:\n  \
        pkm dynamics examples/robots/ur5-like.urdf --q 0,-60,30,0,0,0\n  \
        pkm dynamics examples/robots/ur5-like.urdf --q 0,-60,30,0,0,0 --qd 30,30,30,0,0,0 --qdd 100,0,0,0,0,0 --json\n\n\
        Joint values in deg (mm for a slide), rates per s, accelerations per s^2. The links'\n\
        masses, centres of mass and inertias come from the URDF's <inertial> elements.\n\
        Torques in N m (N for a slide), the drive's on its joint.")]
    Dynamics(DynamicsArgs),
    /// Map the workspace: reachable points, the limit that binds elsewhere, and the
    /// Jacobian's conditioning, on a grid (rayon, all cores).
    #[command(after_help = "Examples:\n  \
        pkm workspace examples/machines/hexapod-linuxcnc.toml --step 20 --out ws\n  \
        pkm workspace examples/machines/hexapod-linuxcnc.toml --orientation 0,10,0 --bounds=-400,400,-400,400,300,800 --step 10 --out ws\n  \
        pkm workspace examples/machines/hexapod-linuxcnc.toml --tilt 15 --step 25 --out total   # reachable at every tilt <= 15 deg\n  \
        pkm workspace examples/machines/hexapod-linuxcnc.toml --at 0,0,550 --out tilt          # orientation workspace at a point\n  \
        pkm workspace examples/machines/hexapod-linuxcnc.toml --step 25 --stiffness --out stiff    # stiffness map (N/um)\n\n\
        Writes DIR/summary.json (measure and measure_unit, volume_mm3 over X, Y, Z, bounding_box, reachable_fraction, condition\n\
        statistics, points per binding limit), DIR/points.csv (DIR/points.parquet with\n\
        --format parquet), DIR/points.ply and slice heat maps.")]
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
    Errors(Box<ErrorsArgs>),
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
    #[command(
        long_about = "Write the HTML report of any machine file: its drawing, kinematic checks, \
        workspace over its whole reach, a path through it, accuracy and (strut machines) \
        calibration, to DIR/index.html (one file, opens offline).\n\n\
        Each section is computed on its own: one that fails shows its error in its place, the \
        others are written, and the exit code is 4. The machine file's [report] table sets \
        defaults (docs/machine-file.md); the options below override it.",
        after_help = "Examples:\n  \
        pkm report                       # bundled seed-000 tripod, writes pkm-report/index.html\n  \
        pkm report examples/machines/tripod-seed000.toml --out my-report\n  \
        pkm report my-hexapod.toml --gcode part.ngc --feeds 1000,5000\n  \
        pkm report my-hexapod.toml --sections drawing,workspace --bounds=-300,300,-300,300,300,900 --step 10"
    )]
    Report(ReportArgs),
    /// Convert another program's machine description into a pkm machine file.
    #[command(subcommand)]
    Import(commands::linuxcnc::ImportFrom),
    /// Write a machine for another program (a controller's configuration).
    #[command(subcommand)]
    Export(commands::linuxcnc::ExportTo),
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

pub fn parse_convention(s: &str) -> Result<Convention, String> {
    s.parse::<Convention>().map_err(|e| e.to_string())
}

/// A reader that stops reading (`pkm ... | head`) ends the command quietly, as it does
/// any Unix tool: SIGPIPE back to its default action. Rust ignores it, so every
/// write after the pipe closed would fail with "Broken pipe" (`out`).
fn quiet_on_closed_pipe() {
    #[cfg(unix)]
    // SAFETY: called first in `main`, before any thread exists; SIG_DFL is a valid
    // disposition for SIGPIPE.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// Clap's help, version or usage error, printed: help and version to standard output,
/// where a failed write is an error (exit 1), usage errors to standard error.
fn command_line_error(e: &clap::Error) -> ExitCode {
    let printed = e
        .print()
        .and_then(|()| std::io::Write::flush(&mut std::io::stdout()));
    match printed {
        Err(io) if !e.use_stderr() => failure(&out::StdoutError(io).into()),
        _ => ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(2)),
    }
}

fn main() -> ExitCode {
    quiet_on_closed_pipe();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return command_line_error(&e),
    };
    // A PKM_SIMD the kernels could not follow (a level this CPU lacks, a typo).
    if let Some(note) = pkm::simd::environment_note() {
        eprintln!("pkm: {note}");
    }
    let res = match cli.command {
        Command::Ik(a) => commands::ik::run(&a),
        Command::Fk(a) => commands::fk::run(&a),
        Command::Check(a) => commands::check::run(&a),
        Command::Motion(a) => commands::motion::run(&a),
        Command::Statics(a) => commands::statics::run(&a),
        Command::Dynamics(a) => commands::dynamics::run(&a),
        Command::Workspace(a) => commands::workspace::run(&a),
        Command::Errors(a) => commands::errors::run(&a),
        Command::SimulateMeasurements(a) => commands::calibrate::simulate_run(&a),
        Command::Calibrate(a) => commands::calibrate::calibrate_run(&a),
        Command::Report(a) => report::run(&a),
        Command::Import(a) => commands::linuxcnc::import_run(&a),
        Command::Export(a) => commands::linuxcnc::export_run(&a),
    };
    // What is still buffered is written now, and its failure reported, before the
    // command's outcome: an answer lost on the way out is no success.
    let res = res.and_then(|code| out::flush().map(|()| code).map_err(Into::into));
    match res {
        Ok(code) => ExitCode::from(code),
        Err(e) => failure(&e),
    }
}

/// Reports `e` on standard error and gives its exit code.
fn failure(e: &anyhow::Error) -> ExitCode {
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
    // A malformed value on the command line, or a pose with the wrong number of
    // values for this machine: a bad command line.
    let bad_argument = e.downcast_ref::<poses::BadArgument>().is_some()
        || matches!(
            e.downcast_ref::<pkm::Error>(),
            Some(pkm::Error::InvalidInput { what, .. }) if what == "pose"
        );
    ExitCode::from(if unreachable {
        EXIT_UNREACHABLE
    } else if bad_argument {
        2
    } else {
        1
    })
}
