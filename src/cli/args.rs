//! The arguments of every subcommand (clap derive) and the parsers of their
//! values: what the command line accepts, apart from what the commands do.
//! The doc comments here are the `--help` text.

use leafmagic::leaf::AeroLawName;
use leafmagic::leaf::plates::{PAPER_AREAL_DENSITY, PlateShape};
use leafmagic::motion::classify::MotionClass;
use leafmagic::physics::params::{Integrator, TimeStep};
use leafmagic::sim::stress::{self, ExplicitPolicy};
use std::path::PathBuf;

/// Arguments of `breed`.
#[derive(clap::Args, Debug)]
pub struct BreedArgs {
    /// Prototype: `a`, `b` (embedded), a leaf file, or `auto`: the embedded one whose
    /// variants most often fall in the target class (A for floaters and autorotating
    /// spinners, B for lilters and tumblers); the choice and its reason are printed.
    #[arg(long, default_value = "auto")]
    pub prototype: String,
    /// Variation scale of generation 0's copies of the prototype (1 = the paper's first
    /// round); the other half of generation 0 is drawn uniformly over the prototype's bounds.
    #[arg(long, default_value_t = 1.0)]
    pub initial_scale: f64,
    /// Start from an earlier run of the same prototype: its archive's leaves (or, without
    /// an archive, its last generation's, best first) take the first places of generation
    /// 0's uniform half. With `--prototype auto`, that run's prototype is used.
    #[arg(long, value_name = "RUN_DIR")]
    pub start_from: Option<PathBuf>,
    /// Motion class to breed toward: floater, spinner or lilter [default: floater; with
    /// --target-features, none: any class may come close].
    #[arg(long, value_parser = parse_target)]
    pub target: Option<MotionClass>,
    /// Individuals per generation.
    #[arg(long, default_value_t = 100)]
    pub population: usize,
    /// Generations in all (generation 0, the prototype's varied copies, counts).
    #[arg(long, default_value_t = 8)]
    pub generations: usize,
    /// Seed of every random stream (same seed, same bytes).
    #[arg(long, default_value_t = 1991)]
    pub seed: u64,
    /// Simulated seconds of each drop.
    #[arg(long, default_value_t = 10.0)]
    pub seconds: f64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Run directory (default: runs/<prototype>-<target>-s<seed>-n<population>-g<generations>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Keep a MAP-Elites archive: the best leaf per cell of descent speed × rotation rate.
    #[arg(long)]
    pub archive: bool,
    /// Breed toward the motion of this fall (CSV by header names: t,x,y,z, optional
    /// qw,qx,qy,qz and area columns; or an animation file, .glb, .gltf, .usd, .usda, .usdc, .usdz or .abc): its class and the descriptors its record measures
    /// (with orientation: descent, spin, tumble, flips, reversals, drift, period, spreads;
    /// positions only: descent, drift, and tumble from the areas).
    #[arg(long, value_name = "TRAJ.csv", conflicts_with_all = ["target", "target_features"])]
    pub like: Option<PathBuf>,
    /// The example's chord, metres, for --like [default: an animation file's own, else the prototype's chord].
    #[arg(long, requires = "like")]
    pub size: Option<f64>,
    /// The --like CSV's vertical axis: z (leafmagic's), y (turned to z up on reading), or -y (a y that points down, as image rows do; write --up=-y).
    #[arg(
        long,
        default_value = "z",
        requires = "like",
        allow_hyphen_values = true
    )]
    pub up: leafmagic::motion::trajectory::UpAxis,
    /// Metres per unit of the --like CSV's x, y, z (a tracker's pixels: the metres one pixel spans in the plane of the fall).
    #[arg(long, default_value_t = 1.0, requires = "like")]
    pub scale: f64,
    /// The --like CSV's t counts frames at this rate (frames per second), not seconds.
    #[arg(long, requires = "like")]
    pub frame_rate: Option<f64>,
    /// The object to read from a --like animation file that animates several.
    #[arg(long, requires = "like")]
    pub object: Option<String>,
    /// What a --like animation file's reading may reach.
    #[command(flatten)]
    pub reading: ReadingArgs,
    /// The animation to read from a --like glTF file whose animations move the same object.
    #[arg(long, requires = "like")]
    pub animation: Option<String>,
    /// Breed toward descriptors given in SI units, e.g. `descent=0.6,spin=20` (m/s, rad/s;
    /// unset ones are free), within the class of --target if given (else any class).
    #[arg(long, value_name = "NAME=VALUE,...")]
    pub target_features: Option<String>,
    /// Release attitudes each leaf is dropped from (tilts of 2–30° about directions drawn
    /// from the leaf's own seed); its score is the lower median of theirs, and how many of
    /// them keep the target class is its robustness (the `kept` column).
    #[arg(long, default_value_t = leafmagic::breed::settings::DEFAULT_RELEASES)]
    pub releases: usize,
    /// Who breeds the children: the genetic algorithm, CMA-ES (per-gene step sizes and
    /// correlations) from generation 1, or the GA until the target class is found and then
    /// mostly CMA-ES, the GA's share keeping other classes reachable.
    #[arg(long, value_enum, default_value_t = StrategyKind::Hybrid)]
    pub strategy: StrategyKind,
    /// Who evaluates each generation (the run's files are the same bytes with any).
    #[arg(long, value_enum, default_value_t = ExecutorKind::Local)]
    pub executor: ExecutorKind,
    /// Shards per generation with --executor processes (default: the cores) or slurm
    /// (default: SLURM_NTASKS of the allocation). --threads is then per shard.
    #[arg(long)]
    pub shards: Option<usize>,
    /// Write the run directory (run.toml) and stop: the generations are then evaluated by
    /// `leafmagic shard` tasks and merged with `leafmagic merge` (Kubernetes, hand-run arrays).
    #[arg(long, conflicts_with_all = ["resume", "executor", "shards", "threads"])]
    pub create_only: bool,
    /// Refuse a run whose estimated work (particles × steps of every drop) exceeds this.
    #[arg(long, default_value_t = leafmagic::physics::run::MAX_BREED_WORK, value_parser = parse_work)]
    pub max_work: f64,
    /// Aerodynamic law the prototype and every variant fall under, over the prototype's [aero]:
    /// `paper` (the paper's linear law, eq. 9–10; a prototype of another law gets αⁿ = 0.47,
    /// αᵗ = 0.047) or `real` (the unsteady law validated against real paper, default
    /// coefficients) [default: the prototype's; the embedded prototypes': paper]. run.toml
    /// records it; with --resume it must be the run's. `linear`, `unsteady`, `quadratic` are
    /// accepted too.
    #[arg(long)]
    pub law: Option<LawArg>,
    /// Finish the run in this directory (after a kill, or to extend nothing: a complete run just reports).
    #[arg(long, conflicts_with_all = ["prototype", "target", "population", "generations", "seed", "seconds", "out", "archive", "like", "size", "target_features", "releases", "strategy", "initial_scale", "start_from"])]
    pub resume: Option<PathBuf>,
}

/// Who breeds the children of `breed` ([`leafmagic::breed::settings::Strategy`]).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum StrategyKind {
    /// The genetic algorithm: tournaments and mutation with the 1/5 success rule.
    Ga,
    /// CMA-ES alone from generation 1, started at generation 0's best.
    Cmaes,
    /// The GA until the target class is found, then two thirds CMA-ES.
    Hybrid,
    /// Random search (a baseline): every leaf a uniform draw over the prototype's bounds.
    Random,
}

impl From<StrategyKind> for leafmagic::breed::settings::Strategy {
    fn from(k: StrategyKind) -> Self {
        use leafmagic::breed::settings::Strategy;
        match k {
            StrategyKind::Ga => Strategy::Ga,
            StrategyKind::Cmaes => Strategy::Cmaes,
            StrategyKind::Hybrid => Strategy::Hybrid,
            StrategyKind::Random => Strategy::Random,
        }
    }
}

/// `--law`: the aerodynamic law a leaf falls under, named for the user:
/// the paper's, or the one validated against real paper. The leaf files'
/// names (`linear`, `unsteady`, `quadratic`) are accepted as aliases, so
/// `plate --law unsteady` scripts keep working.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum LawArg {
    /// The paper's linear law (eq. 9–10).
    #[value(alias = "linear")]
    Paper,
    /// The unsteady law validated against real paper squares.
    #[value(alias = "unsteady")]
    Real,
    /// Quadratic drag with lift (a reference, not validated).
    Quadratic,
}

impl LawArg {
    /// The library's name of the law.
    pub fn law(self) -> AeroLawName {
        match self {
            LawArg::Paper => AeroLawName::Linear,
            LawArg::Real => AeroLawName::Unsteady,
            LawArg::Quadratic => AeroLawName::Quadratic,
        }
    }
}

/// The word `--law` uses for a leaf file's law, as outputs print it.
pub fn law_word(law: AeroLawName) -> &'static str {
    match law {
        AeroLawName::Linear => "paper",
        AeroLawName::Unsteady => "real",
        AeroLawName::Quadratic => "quadratic",
    }
}

/// Who evaluates each generation of `breed`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExecutorKind {
    /// This process's thread pool.
    Local,
    /// `--shards` child processes (`leafmagic shard`) on this machine.
    Processes,
    /// Slurm: one `srun` step per generation inside an allocation (sbatch/salloc the driver),
    /// else one `sbatch --wait --array` per generation.
    Slurm,
}

/// Arguments of `export`.
#[derive(clap::Args, Debug)]
pub struct ExportArgs {
    /// A breeding run directory.
    pub run: PathBuf,
    /// Export the K best of the last generation.
    #[arg(long, conflicts_with = "ids")]
    pub top: Option<usize>,
    /// Export these individuals of the last generation (comma-separated ids).
    #[arg(long, value_delimiter = ',')]
    pub ids: Option<Vec<u64>>,
    /// Output directory for the leaf files and index.csv.
    #[arg(long)]
    pub out: PathBuf,
    /// Also re-drop each leaf as breeding dropped it and write its fall:
    /// `glb` (leaf-<id>.glb), `pc2` (leaf-<id>.pc2 + leaf-<id>.obj), `usd`
    /// (leaf-<id>.usda) or `abc` (leaf-<id>.abc, Alembic).
    #[arg(long)]
    pub format: Option<leafmagic::formats::Format>,
    /// Frames per second of the exported motion.
    #[arg(long, default_value_t = leafmagic::formats::clip::DEFAULT_FPS)]
    pub fps: f64,
    /// Release height of each exported fall, m (z up): the leaf starts
    /// here instead of at the origin.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub start_height: f64,
    /// A finer textured mesh (OBJ with UVs, in the prototype leaf file's
    /// coordinates) to export in place of the simulated one, bound to it.
    #[arg(long)]
    pub render_mesh: Option<PathBuf>,
    /// The frame rate of the scene the export is played in: USD's time
    /// codes count its frames, and a PC2 cache's samples are spaced
    /// host-fps / fps of them apart, so both play in real time.
    #[arg(long, default_value_t = leafmagic::formats::pc2::DEFAULT_HOST_FPS)]
    pub host_fps: f64,
}

/// Arguments of `drop`.
#[derive(clap::Args, Debug)]
pub struct DropArgs {
    /// Leaf file (TOML), or `a` / `b` for the embedded prototypes.
    pub leaf: String,
    /// Time integrator.
    #[arg(long, default_value = "verlet")]
    pub integrator: Integrator,
    /// Time step in seconds, or `auto` (from the stability estimate).
    #[arg(long, default_value = "auto", value_parser = parse_dt)]
    pub dt: TimeStep,
    /// Simulated seconds.
    #[arg(long, default_value_t = 10.0)]
    pub seconds: f64,
    /// Release tilt about the leaf's x and y axes, degrees (`--tilt -4,2`
    /// as well as `--tilt=-4,2`).
    #[arg(long, default_value = "10,2", value_parser = parse_tilt, allow_hyphen_values = true)]
    pub tilt: [f64; 2],
    /// Write the trajectory (t,x,y,z,qw,qx,qy,qz at 240 Hz) to this CSV file.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Also write every particle's position per frame to this CSV file.
    #[arg(long)]
    pub particles: Option<PathBuf>,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Refuse a drop whose estimated work (particles × steps) exceeds this.
    #[arg(long, default_value_t = leafmagic::physics::run::MAX_WORK, value_parser = parse_work)]
    pub max_work: f64,
    /// Aerodynamic law, over the leaf file's [aero]: `paper` (the paper's linear law, eq. 9–10;
    /// a leaf of another law gets the prototypes' αⁿ = 0.47, αᵗ = 0.047) or `real` (the
    /// unsteady law validated against real paper, default coefficients) [default: the file's;
    /// the embedded prototypes': paper]. `linear`, `unsteady` and `quadratic` are accepted too.
    #[arg(long)]
    pub law: Option<LawArg>,
}

/// Arguments of `check`.
#[derive(clap::Args, Debug)]
pub struct CheckArgs {
    /// Leaf file (TOML), or `a` / `b` for the embedded prototypes.
    pub leaf: String,
    /// Print JSON instead of a table (with --stress: an array of one object per row).
    #[arg(long)]
    pub json: bool,
    /// Run the stiff and extreme matrix: every stress case with every integrator.
    #[arg(long)]
    pub stress: bool,
    /// With --stress: what explicit integrators do with a step above their stable estimate.
    #[arg(long, default_value = "substep", value_parser = parse_policy)]
    pub explicit: ExplicitPolicy,
    /// With --stress --explicit substep: the most sub-steps per step (a warning says when it clamps).
    #[arg(long, default_value_t = stress::DEFAULT_SUBSTEP_CAP)]
    pub substep_cap: u64,
    /// Aerodynamic law, over the leaf file's [aero]: `paper` (the paper's linear law, eq. 9–10;
    /// a leaf of another law gets the prototypes' αⁿ = 0.47, αᵗ = 0.047) or `real` (the
    /// unsteady law validated against real paper, default coefficients) [default: the file's;
    /// the embedded prototypes': paper]. `linear`, `unsteady` and `quadratic` are accepted too.
    #[arg(long)]
    pub law: Option<LawArg>,
}

/// Arguments of `plate`.
#[derive(clap::Args, Debug)]
pub struct PlateArgs {
    /// Outline: square, circle, hexagon, rectangle or cross.
    #[arg(long)]
    pub shape: PlateShape,
    /// Twice the inradius, metres: a square's side, a circle's diameter, a
    /// hexagon's flat-to-flat width, a rectangle's width (short side); a
    /// cross's span, tip to tip.
    #[arg(long, allow_negative_numbers = true)]
    pub size: f64,
    /// Length over width (rectangles only; at least 1).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub aspect: f64,
    /// The width of each of a cross's two arms, metres (crosses only, and
    /// required for them; above 0 and below --size).
    #[arg(long, allow_negative_numbers = true)]
    pub arm_width: Option<f64>,
    /// Mass per area, kg/m² (70 g/m² paper by default).
    #[arg(long, default_value_t = PAPER_AREAL_DENSITY, allow_negative_numbers = true)]
    pub areal_density: f64,
    /// Aerodynamic law: `real` (the unsteady law validated against real paper), `paper` (the
    /// paper's linear law, with its prototypes' αⁿ = 0.47, αᵗ = 0.047) or `quadratic`; the old
    /// names `unsteady` and `linear` are accepted too.
    #[arg(long, default_value = "real")]
    pub law: LawArg,
    /// Make the plate a sheet that bends, of this bending stiffness D =
    /// E t³/12(1 − ν²), N·m (70 g/m² paper: about 2.5e-4), instead of one
    /// rigid body: hinges on every shared edge, springs on every edge.
    // Hyphen values, so that a negative one in any notation (-1e-4) is
    // refused for its value rather than read as a flag.
    #[arg(long, allow_hyphen_values = true)]
    pub bending_stiffness: Option<f64>,
    /// Leaf file to write (standard output if absent).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// How far an animation file's reading may reach: the folders its
/// references may resolve into and the memory it may take.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct ReadingArgs {
    /// Let an animation file's references (glTF buffers and images, USD sublayers, references and payloads) reach into DIR too, as USD's search paths do; by default they resolve only inside the file's own folder. Repeatable.
    #[arg(long = "allow-references", value_name = "DIR")]
    pub allow_references: Vec<PathBuf>,
    /// The most memory reading an animation file may take, bytes [default: 4.3e9].
    #[arg(long = "max-memory", value_name = "BYTES", value_parser = parse_work)]
    pub max_memory: Option<f64>,
}

impl ReadingArgs {
    /// The library's reading policy these flags give.
    pub fn policy(&self) -> leafmagic::util::confined::ReadPolicy {
        let mut policy = leafmagic::util::confined::ReadPolicy {
            also_allowed: self.allow_references.clone(),
            ..Default::default()
        };
        if let Some(bytes) = self.max_memory {
            policy.max_memory = bytes.min(u64::MAX as f64) as u64;
        }
        policy
    }
}

/// Arguments of `classify` and `describe`: one recorded fall.
#[derive(clap::Args, Debug)]
pub struct FallArgs {
    /// Fall CSV, columns by header name in any order: t,x,y,z required (or t, the vertical and one horizontal: one camera's view, read in its vertical plane); qw,qx,qy,qz (body to world, w first) and area columns (area, area1, ...) optional. Or an animation file (glTF .glb/.gltf, USD .usd/.usda/.usdc/.usdz, Alembic .abc: leafmagic's export, a Blender, Houdini or game-engine bake), read at its keys: the moving mesh's centre and principal axes, whether its own keys, parents, morph targets or bones move it.
    pub trajectory: PathBuf,
    /// The leaf's size, metres: a square's side or a leaf's length, as the tracked records give it; sets the length scale of the tests [default: 0.05, or an animation file's mesh's longest extent].
    #[arg(long)]
    pub size: Option<f64>,
    /// A CSV's vertical axis: z (leafmagic's), y (turned to z up on reading), or -y (a y that points down, as image rows do; write --up=-y); glTF is y up by its specification, USD says its own.
    #[arg(long, default_value = "z", allow_hyphen_values = true)]
    pub up: leafmagic::motion::trajectory::UpAxis,
    /// Metres per unit of a CSV's x, y, z (a tracker's pixels: the metres one pixel spans in the plane of the fall), or of an Alembic archive's lengths (it carries no unit: 0.01 for Maya's centimetres).
    #[arg(long, default_value_t = 1.0)]
    pub scale: f64,
    /// A CSV's t counts frames at this rate (frames per second), not seconds.
    #[arg(long)]
    pub frame_rate: Option<f64>,
    /// The object to read from an animation file that animates several (its glTF node's name, its USD prim's or Alembic object's path, an instancer's leaf as INSTANCER[ID]).
    #[arg(long)]
    pub object: Option<String>,
    /// The animation to read from a glTF file whose animations move the same object (Blender writes each action of an object as one; by name, or index).
    #[arg(long)]
    pub animation: Option<String>,
    /// What an animation file's reading may reach.
    #[command(flatten)]
    pub reading: ReadingArgs,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `classify`: one recorded fall, or every fall of an
/// animation file.
#[derive(clap::Args, Debug)]
pub struct ClassifyArgs {
    /// The fall, and how to read it.
    #[command(flatten)]
    pub fall: FallArgs,
    /// Classify every fall of an animation file (each moving mesh, and each particle of an Alembic points cache) and print one line each with the counts per class, instead of naming one with --object.
    #[arg(long, conflicts_with = "object")]
    pub all: bool,
    /// The classes each fall should have, comma-separated (floater, spinner, lilter, undetermined): every fall is checked, each one of another class is named, and the command fails if there is any (for a pipeline's tests).
    #[arg(long, value_delimiter = ',', num_args = 1.., value_name = "CLASS[,CLASS]", value_parser = parse_class)]
    pub expect: Vec<MotionClass>,
    /// Also write the verdicts of --expect as JUnit XML to this file (one testcase per fall, a failure where its class is not expected), for a CI pipeline's test report.
    #[arg(long, value_name = "FILE", requires = "expect")]
    pub junit: Option<PathBuf>,
}

/// Arguments of `accuracy`.
#[derive(clap::Args, Debug)]
pub struct AccuracyArgs {
    /// Leaf file (TOML), or `a` / `b` for the embedded prototypes.
    #[arg(default_value = "a")]
    pub leaf: String,
    /// Simulated seconds T [default: 1, or 10 with --long].
    #[arg(long)]
    pub seconds: Option<f64>,
    /// Directory for accuracy.csv and accuracy.svg (accuracy-long.csv with --long); created if missing. Output goes under runs/, as every command's does, not into the current folder.
    #[arg(long, default_value = "runs/accuracy")]
    pub out: PathBuf,
    /// Compare motion classes and statistics (descent speed, rotation rate) across steps for a long fall.
    #[arg(long)]
    pub long: bool,
    /// Timed runs per point (the median is reported; at least 5 for published figures).
    #[arg(long, default_value_t = leafmagic::sim::accuracy::DEFAULT_RUNS)]
    pub runs: usize,
    /// Use RK4 at T/2^J as the reference, exactly (by default the reference starts three halvings below RK4's smallest step and is halved until it validates; it is checked either way).
    #[arg(long, value_name = "J")]
    pub reference_j: Option<u32>,
    /// The integrators to sweep or compare, comma-separated [default: all five]. The reference is RK4's either way.
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    pub integrators: Vec<Integrator>,
    /// Aerodynamic law, over the leaf file's [aero]: `paper` (the paper's linear law, eq. 9–10;
    /// a leaf of another law gets the prototypes' αⁿ = 0.47, αᵗ = 0.047) or `real` (the
    /// unsteady law validated against real paper, default coefficients) [default: the file's;
    /// the embedded prototypes': paper]. `linear`, `unsteady` and `quadratic` are accepted too.
    #[arg(long)]
    pub law: Option<LawArg>,
}

/// Arguments of `scene`.
#[derive(clap::Args, Debug)]
pub struct SceneArgs {
    /// Scene file (TOML, see scenes/README.md).
    pub file: PathBuf,
    /// Output directory (default runs/scene-<name>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Simulated seconds (default: the scene's duration).
    #[arg(long)]
    pub seconds: Option<f64>,
    /// List what the compiled scene keeps and leaves out, then stop.
    #[arg(long)]
    pub explain: bool,
    /// Also export the run: `glb` (DIR/<scene>.glb), `pc2` (DIR/<object>.pc2
    /// + .obj), `usd` (DIR/<scene>.usda) or `abc` (DIR/<scene>.abc, Alembic).
    #[arg(long)]
    pub export: Option<leafmagic::formats::Format>,
    /// Frames per second of the exported motion.
    #[arg(long, default_value_t = leafmagic::formats::clip::DEFAULT_FPS)]
    pub export_fps: f64,
    /// The frame rate of the scene a USD or PC2 export is played in (USD
    /// time codes count its frames).
    #[arg(long, default_value_t = leafmagic::formats::pc2::DEFAULT_HOST_FPS)]
    pub export_host_fps: f64,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Refuse a scene whose estimated work (particles × steps) exceeds this.
    #[arg(long, default_value_t = leafmagic::physics::run::MAX_WORK, value_parser = parse_work)]
    pub max_work: f64,
    /// Refuse a scene whose recorded frames would take more memory than this many bytes.
    #[arg(long, default_value_t = leafmagic::sim::scene::MAX_MEMORY, value_parser = parse_work)]
    pub max_memory: f64,
    /// Aerodynamic law of every leaf, over each leaf file's [aero]: `paper` (the paper's
    /// linear law, eq. 9–10; a leaf of another law gets the prototypes' αⁿ = 0.47,
    /// αᵗ = 0.047) or `real` (the unsteady law validated against real paper, default
    /// coefficients) [default: the files']. `linear`, `unsteady`, `quadratic` are accepted too.
    #[arg(long)]
    pub law: Option<LawArg>,
}

/// Arguments of `direct`.
#[derive(clap::Args, Debug)]
pub struct DirectArgs {
    /// Scene file with [[goal]] and [[free]] tables (see docs/guide/directing.md).
    pub file: PathBuf,
    /// Scene runs CMA-ES may make; random search, the baseline, makes as many more [default: 200; with --resume, the search's].
    #[arg(long)]
    pub budget: Option<usize>,
    /// Seed of every sample (same seed, same bytes on any number of threads and after kill + resume) [default: 0; with --resume, the search's].
    #[arg(long)]
    pub seed: Option<u64>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Output directory (default runs/direct-<name>-s<seed>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print one JSON object instead of the report.
    #[arg(long)]
    pub json: bool,
    /// Go on with the search whose output directory is DIR (killed or not) from its last whole batch: the same bytes as a search never stopped. The scene file, --budget and --seed must be the search's.
    #[arg(long, value_name = "DIR")]
    pub resume: Option<PathBuf>,
    /// Refuse a search whose estimated work (particles × steps × runs, the baseline's included) exceeds this.
    #[arg(long, default_value_t = leafmagic::physics::run::MAX_BREED_WORK, value_parser = parse_work)]
    pub max_work: f64,
}

/// Arguments of `compare`.
#[derive(clap::Args, Debug)]
pub struct CompareArgs {
    /// First fall (CSV by header names: t,x,y,z, optional qw,qx,qy,qz and area columns; or an animation file, .glb, .gltf, .usd, .usda, .usdc, .usdz or .abc).
    pub a: PathBuf,
    /// Second fall.
    pub b: PathBuf,
    /// The leaves' chord, metres: one for both falls, or A,B (a real square of 4.2 cm against a 5 cm leaf: 0.042,0.05) [default: 0.05, or an animation file's mesh's own].
    #[arg(long)]
    pub size: Option<EachFile<f64>>,
    /// The CSVs' vertical axis, z (leafmagic's), y (turned to z up on reading) or -y (pointing down, as image rows do): one for both, or A,B (a tracker's y-up record against a drop's: y,z).
    #[arg(long, default_value = "z", allow_hyphen_values = true)]
    pub up: EachFile<leafmagic::motion::trajectory::UpAxis>,
    /// Metres per unit of the CSVs' x, y, z: one for both, or A,B (a pixel track against a drop: 0.0004,1).
    #[arg(long, default_value = "1")]
    pub scale: EachFile<f64>,
    /// The CSVs' t counts frames at this rate, not seconds: one for both, or A,B.
    #[arg(long)]
    pub frame_rate: Option<EachFile<f64>>,
    /// The object to read from animation files that animate several: one name for both, or A,B.
    #[arg(long)]
    pub object: Option<EachFile<String>>,
    /// The animation to read from glTF files whose animations move the same object: one name for both, or A,B.
    #[arg(long)]
    pub animation: Option<EachFile<String>>,
    /// What an animation file's reading may reach.
    #[command(flatten)]
    pub reading: ReadingArgs,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

impl FallArgs {
    /// The fall the arguments name, read and classified
    /// ([`super::input::read_fall`]).
    pub fn read(&self) -> anyhow::Result<super::input::Fall> {
        let units = super::input::CsvUnits {
            up: self.up,
            scale: self.scale,
            frame_rate: self.frame_rate,
        };
        let policy = self.reading.policy();
        let pick = super::input::Pick {
            object: self.object.as_deref(),
            animation: self.animation.as_deref(),
            policy: Some(&policy),
        };
        super::input::read_fall(&self.trajectory, self.size, units, pick)
    }
}

impl CompareArgs {
    /// How each file is read if it is a CSV record.
    pub fn units(&self) -> [super::input::CsvUnits; 2] {
        let rate = |pick: fn(EachFile<f64>) -> f64| self.frame_rate.map(pick);
        [
            super::input::CsvUnits {
                up: self.up.0,
                scale: self.scale.0,
                frame_rate: rate(|r| r.0),
            },
            super::input::CsvUnits {
                up: self.up.1,
                scale: self.scale.1,
                frame_rate: rate(|r| r.1),
            },
        ]
    }
}

/// A flag's value for each of two files: `V` for both, or `A,B`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EachFile<T>(pub T, pub T);

impl<T: std::str::FromStr + Clone> std::str::FromStr for EachFile<T>
where
    T::Err: std::fmt::Display,
{
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let one = |v: &str| v.trim().parse::<T>().map_err(|e| format!("`{v}`: {e}"));
        match s.split(',').collect::<Vec<_>>().as_slice() {
            [v] => one(v).map(|v| EachFile(v.clone(), v)),
            [a, b] => Ok(EachFile(one(a)?, one(b)?)),
            _ => Err(format!(
                "`{s}`: one value for both files, or two separated by a comma"
            )),
        }
    }
}

/// Arguments of `preview`.
#[derive(clap::Args, Debug)]
pub struct PreviewArgs {
    /// A breeding run directory, a scene output directory, an animation file (.glb, .gltf, .usd, .usda, .usdc, .usdz, .abc: its falling objects that carry no label are labelled with their class) or a fall record (.csv, as classify reads it: a plate where it has an orientation, a marker where it has a path only, labelled with its class). Several files: side by side on one page, to compare their falls.
    #[arg(required = true, num_args = 1..)]
    pub inputs: Vec<PathBuf>,
    /// The HTML file to write [default: INPUT/preview.html for a directory, INPUT with .html for a file, the first INPUT with .compare.html for several].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// For a breeding run: show the K best leaves of the last generation.
    #[arg(long, default_value_t = 5)]
    pub top: usize,
    /// Frames per second of the embedded motion [default: 30 for a directory; a leafmagic .glb's own rate or 30 for a .glb; the keys' own rate for another file].
    #[arg(long)]
    pub fps: Option<f64>,
    /// The animation to play of a glTF file whose animations move the same object (by name, or index).
    #[arg(long)]
    pub animation: Option<String>,
    /// What an animation file's reading may reach.
    #[command(flatten)]
    pub reading: ReadingArgs,
    /// Metres per unit of an Alembic archive, which carries no unit (0.01 for Maya's centimetres), or of a CSV record's x, y, z [default: 1].
    #[arg(long)]
    pub scale: Option<f64>,
    /// A CSV record's leaf size, metres (a square's side or a leaf's length): the plate drawn and the length scale of its classification [default: 0.05].
    #[arg(long)]
    pub size: Option<f64>,
    /// A CSV record's vertical axis: z, y, or -y (write --up=-y) [default: z].
    #[arg(long, allow_hyphen_values = true)]
    pub up: Option<leafmagic::motion::trajectory::UpAxis>,
    /// A CSV record's t counts frames at this rate (frames per second), not seconds.
    #[arg(long)]
    pub frame_rate: Option<f64>,
}

/// Arguments of `shard`.
#[derive(clap::Args, Debug)]
pub struct ShardArgs {
    /// A breeding run directory (run.toml, and checkpoint.json after generation 0).
    pub run: PathBuf,
    /// The generation to evaluate: the one after the checkpoint's.
    #[arg(long)]
    pub generation: usize,
    /// This shard's index, from 0 [default: from SLURM_PROCID, SLURM_ARRAY_TASK_ID,
    /// JOB_COMPLETION_INDEX or AWS_BATCH_JOB_ARRAY_INDEX].
    #[arg(long, requires = "count")]
    pub index: Option<usize>,
    /// Shards in the generation [default: SLURM_NTASKS or SLURM_ARRAY_TASK_COUNT].
    #[arg(long)]
    pub count: Option<usize>,
    /// Worker threads (default: SLURM_CPUS_PER_TASK, else all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Do nothing if a valid shard file is already there (a rerun keeps finished work).
    #[arg(long)]
    pub skip_done: bool,
}

/// Arguments of `merge`.
#[derive(clap::Args, Debug)]
pub struct MergeArgs {
    /// A breeding run directory.
    pub run: PathBuf,
    /// The generation whose shards to merge (the one after the checkpoint's).
    #[arg(long)]
    pub generation: usize,
    /// Shards in the generation.
    #[arg(long)]
    pub count: usize,
}

/// `--dt`: `auto`, or a positive, finite number of seconds.
fn parse_dt(s: &str) -> Result<TimeStep, String> {
    if s == "auto" {
        return Ok(TimeStep::Auto);
    }
    let h: f64 = s
        .parse()
        .map_err(|_| format!("expected a number of seconds or 'auto', got '{s}'"))?;
    if h > 0.0 && h.is_finite() {
        Ok(TimeStep::Fixed(h))
    } else {
        Err(format!(
            "the time step must be a positive number of seconds, got {s}"
        ))
    }
}

/// `--max-work`, `--max-memory`: a positive number (`1e10` is fine).
fn parse_work(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v > 0.0 && !v.is_nan() => Ok(v),
        _ => Err(format!(
            "expected a positive number such as 1e10, got '{s}'"
        )),
    }
}

/// `--target`: a class a leaf can be bred toward; `undetermined` is what
/// a fall is called when it is none of them, so it is no target.
fn parse_target(s: &str) -> Result<MotionClass, String> {
    match s.parse::<MotionClass>() {
        Ok(MotionClass::Undetermined) | Err(_) => {
            Err(format!("expected floater, spinner or lilter, got '{s}'"))
        }
        Ok(class) => Ok(class),
    }
}

/// `--expect`: a class by name (any of the four, undetermined too).
fn parse_class(s: &str) -> Result<MotionClass, String> {
    s.parse::<MotionClass>().map_err(|e| e.to_string())
}

/// `--tilt`: `X,Y` degrees, or `X` alone (Y is then 0).
fn parse_tilt(s: &str) -> Result<[f64; 2], String> {
    let parts: Vec<&str> = s.split(',').collect();
    let parse = |p: &str| {
        p.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("expected degrees as 'X,Y', got '{s}'"))
    };
    match parts.as_slice() {
        [x] => Ok([parse(x)?, 0.0]),
        [x, y] => Ok([parse(x)?, parse(y)?]),
        _ => Err(format!("expected degrees as 'X,Y', got '{s}'")),
    }
}

/// `--explicit`: `refuse` or `substep`, as the library parses them.
fn parse_policy(s: &str) -> Result<ExplicitPolicy, leafmagic::sim::stress::UnknownPolicy> {
    s.parse()
}

/// Arguments of `studio`.
#[derive(clap::Args, Debug)]
pub struct StudioArgs {
    /// Prototype: `a`, `b` (embedded) or a leaf file.
    #[arg(long, default_value = "a")]
    pub prototype: String,
    /// The class each fall is scored against (what "kept k of K" counts): floater, spinner or lilter.
    #[arg(long, default_value = "floater", value_parser = parse_target)]
    pub target: MotionClass,
    /// Seed of every random stream (same seed and same picks, same files).
    #[arg(long, default_value_t = 1991)]
    pub seed: u64,
    /// Port on 127.0.0.1 [default: any free one].
    #[arg(long, default_value_t = 0)]
    pub port: u16,
    /// Candidates per generation, 4 to 20.
    #[arg(long, default_value_t = 12)]
    pub grid: usize,
    /// Simulated seconds of each drop.
    #[arg(long, default_value_t = 10.0)]
    pub seconds: f64,
    /// The session directory [default: runs/studio-<prototype>-s<seed>].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Aerodynamic law of the prototype and every candidate, over the prototype's [aero]:
    /// `paper` (the paper's linear law; a prototype of another law gets αⁿ = 0.47,
    /// αᵗ = 0.047) or `real` (the unsteady law validated against real paper) [default: the
    /// prototype's; the embedded ones': paper]. `linear`, `unsteady`, `quadratic` are accepted too.
    #[arg(long)]
    pub law: Option<LawArg>,
    /// Reopen the session in DIR where it was (its own settings apply).
    #[arg(long, value_name = "DIR", conflicts_with_all = ["prototype", "target", "seed", "grid", "seconds", "out", "law"])]
    pub resume: Option<PathBuf>,
    /// An example fall (a CSV record `t,x,y,z[,qw,qx,qy,qz]` in seconds and metres, z up, or an animation file) shown beside the kept leaves and bred toward by Auto N; read once, at the start.
    #[arg(long, value_name = "FILE", conflicts_with = "resume")]
    pub like: Option<PathBuf>,
    /// Open the page in the desktop's browser (xdg-open).
    #[arg(long)]
    pub open: bool,
}
