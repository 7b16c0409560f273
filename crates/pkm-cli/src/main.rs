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
