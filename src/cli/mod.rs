//! The command line: it parses the arguments, calls the library and prints
//! what comes back; everything that computes lives in the library. It is
//! the top layer and may use every library layer; none of them uses it.
//!
//! `args` is what each subcommand accepts; `breed`, `drop`, `accuracy`,
//! `motion`, `scene`, `direct` and `output` do the commands' work (with `input`, the
//! loading they share, and `progress`, the bar of `breed`); `report` formats
//! what a person reads, `words` names the library's settings as flags. This file: the top-level parser and the dispatch.

mod accuracy;
mod args;
mod breed;
mod direct;
mod drop;
mod input;
mod motion;
mod output;
mod plate;
mod progress;
mod report;
mod scene;
mod studio;
mod words;

use anyhow::Result;
use args::{
    AccuracyArgs, BreedArgs, CheckArgs, ClassifyArgs, CompareArgs, DirectArgs, DropArgs,
    ExportArgs, FallArgs, MergeArgs, PlateArgs, PreviewArgs, SceneArgs, ShardArgs, StudioArgs,
};
use clap::{Parser, Subcommand};

/// Breed falling-leaf motion in a mass-spring simulator with potential-flow wind.
#[derive(Parser, Debug)]
#[command(name = "leafmagic", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Breed leaf variants toward a motion class (the paper's section 4.1, automated).
    Breed(BreedArgs),
    /// Write chosen leaves of a breeding run as leaf files.
    Export(ExportArgs),
    /// Drop a leaf from rest in still air and record its fall.
    Drop(DropArgs),
    /// Write a flat plate (square, circle, hexagon, rectangle or cross) of paper as a
    /// leaf file: a uniform rigid plate, 70 g/m² and the unsteady law by default.
    Plate(PlateArgs),
    /// Report the stable time step of a leaf for each integrator, with warnings.
    Check(CheckArgs),
    /// Name the motion of a recorded fall (CSV by header names: t,x,y,z; orientation
    /// and projected areas optional).
    Classify(ClassifyArgs),
    /// The motion descriptors of one recorded fall (what `breed --like` and
    /// `compare` steer by), with which of them the record lets one measure.
    Describe(FallArgs),
    /// Error against cost of every integrator over a sweep of time steps
    /// (work-precision), or with --long, classes and statistics across steps.
    Accuracy(AccuracyArgs),
    /// Run a scene file and write per-object trajectories and a summary.
    Scene(SceneArgs),
    /// Search a scene's free parameters (wind strengths, positions, leaf releases) for values
    /// that meet its goals (where and when the leaves go): CMA-ES, with random search as baseline.
    Direct(DirectArgs),
    /// Motion descriptors of two falls side by side, and their distance.
    Compare(CompareArgs),
    /// Write one self-contained HTML page that plays a breeding run's best
    /// leaves, a scene's output or a .glb file in 3-D (works offline).
    Preview(PreviewArgs),
    /// Choose leaves by eye in the browser and breed from the picks: a local web server
    /// with a grid of falling candidates (see docs/guide/studio.md).
    Studio(StudioArgs),
    /// Evaluate one shard of a generation of a breeding run and write its shard file
    /// (what `breed --executor processes|slurm` starts; see docs/reference.md, "Beyond one machine").
    Shard(ShardArgs),
    /// Merge the shard files of a generation that something else evaluated (a Kubernetes
    /// Indexed Job, a Slurm array) into the run: its files and checkpoint, as breed would.
    Merge(MergeArgs),
    /// Compose a USD stage and print it as one flat layer in JSON: what
    /// reading a binary, packaged or composed USD file runs in a child
    /// process (src/output/export/usd_stage.rs says why).
    #[command(hide = true)]
    ComposeUsd {
        /// The USD file.
        file: std::path::PathBuf,
        /// A folder its layers may come from besides its own (the
        /// reader's --allow-references); repeated.
        #[arg(long = "root")]
        roots: Vec<std::path::PathBuf>,
        /// The process that asked: when it is gone, this one ends.
        #[arg(long)]
        parent: Option<u32>,
        /// Wall-clock bound, seconds.
        #[arg(long = "timeout-s")]
        timeout_s: Option<f64>,
    },
}

/// Runs the parsed command.
pub fn run(cli: Cli) -> Result<()> {
    // The library's messages name settings; here they are flags.
    leafmagic::util::setting::spell_with(&words::Flags);
    match cli.command {
        Command::Breed(args) => breed::breed(args),
        Command::Export(args) => output::export(args),
        Command::Drop(args) => drop::drop(args),
        Command::Check(args) => drop::check(args),
        Command::Plate(args) => plate::plate(args),
        Command::Classify(args) => motion::classify(args),
        Command::Describe(args) => motion::describe(args),
        Command::Accuracy(args) => accuracy::accuracy(args),
        Command::Scene(args) => scene::scene(args),
        Command::Direct(args) => direct::direct(args),
        Command::Compare(args) => motion::compare(args),
        Command::Preview(args) => output::preview(args),
        Command::Studio(args) => studio::studio(args),
        Command::Shard(args) => breed::shard(args),
        Command::Merge(args) => breed::merge(args),
        Command::ComposeUsd {
            file,
            roots,
            parent,
            timeout_s,
        } => output::compose_usd(leafmagic::formats::usd::ComposeRequest {
            file,
            roots,
            parent,
            timeout: timeout_s
                .filter(|s| s.is_finite() && *s > 0.0 && *s < 1e9)
                .map(std::time::Duration::from_secs_f64),
        }),
    }
}
