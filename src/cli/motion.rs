//! `classify`, `describe` and `compare`: what a recorded fall shows, the
//! numbers `breed --like` steers by, and how far apart two falls are.

use super::args::{ClassifyArgs, CompareArgs, EachFile, FallArgs};
use super::{input, report};
use anyhow::{Context, Result, bail};
use leafmagic::motion::class::MotionClass;
use leafmagic::motion::classify::Classification;
use leafmagic::motion::describe::{self, Descriptors};
use serde_json::json;
use std::path::Path;

/// `classify`: names the motion of a recorded fall, or with `--all` of
/// every fall of an animation file.
pub fn classify(args: ClassifyArgs) -> Result<()> {
    let expectation = Expectation::of(&args);
    if args.all {
        return classify_all(&args.fall, expectation.as_ref());
    }
    let args = &args.fall;
    let fall = args.read()?;
    let (traj, c) = (&fall.record.trajectory, &fall.classification);
    if args.json {
        // The classification's own fields in their order, then the notes
        // and, with --expect, the verdict.
        #[derive(serde::Serialize)]
        struct Noted<'a> {
            #[serde(flatten)]
            classification: &'a leafmagic::motion::classify::Classification,
            #[serde(flatten)]
            notes: ReadingNotes<'a>,
            #[serde(skip_serializing_if = "Option::is_none")]
            expected: Option<Vec<&'static str>>,
            #[serde(skip_serializing_if = "Option::is_none")]
            as_expected: Option<bool>,
        }
        let noted = Noted {
            classification: c,
            notes: ReadingNotes::of(&fall),
            expected: expectation.as_ref().map(Expectation::names),
            as_expected: expectation.as_ref().map(|e| e.holds(c.class)),
        };
        println!("{}", serde_json::to_string_pretty(&noted)?);
    } else {
        print!(
            "{}",
            report::motion::classified(&args.trajectory, traj.len(), c)
        );
    }
    match &expectation {
        Some(e) => {
            // A CSV record is its file; an object is named as in the file.
            let name = match fall.record.object.as_deref() {
                Some(object) => object.to_string(),
                None => args.trajectory.display().to_string(),
            };
            e.check(&args.trajectory, &[(name, c)], args.json)
        }
        None => Ok(()),
    }
}

/// `classify --expect` (and `--junit`): the classes every fall should
/// have, and where to write the verdicts for a CI pipeline.
struct Expectation<'a> {
    /// The expected classes, each once, in the order given.
    classes: Vec<MotionClass>,
    junit: Option<&'a Path>,
}

impl<'a> Expectation<'a> {
    /// The expectation `--expect` sets, if it is given.
    fn of(args: &'a ClassifyArgs) -> Option<Expectation<'a>> {
        if args.expect.is_empty() {
            return None;
        }
        let mut classes = Vec::new();
        for &c in &args.expect {
            if !classes.contains(&c) {
                classes.push(c);
            }
        }
        Some(Expectation {
            classes,
            junit: args.junit.as_deref(),
        })
    }

    /// Whether a fall of `class` is as expected.
    fn holds(&self, class: MotionClass) -> bool {
        self.classes.contains(&class)
    }

    /// The expected classes' names.
    fn names(&self) -> Vec<&'static str> {
        self.classes.iter().map(|c| c.as_str()).collect()
    }

    /// The expected classes in words: `floater or spinner`.
    fn either(&self) -> String {
        report::motion::either(&self.classes)
    }

    /// Judges `falls` (name, classification) of `file`: prints the
    /// verdicts (unless the output is JSON, which carries them), writes the
    /// JUnit report if asked, and fails naming every fall of another class.
    fn check(&self, file: &Path, falls: &[(String, &Classification)], json: bool) -> Result<()> {
        use leafmagic::output::junit::{TestCase, junit_xml};
        let wrong: Vec<&(String, &Classification)> =
            falls.iter().filter(|(_, c)| !self.holds(c.class)).collect();
        if !json {
            print!(
                "{}",
                report::motion::verdicts(&self.classes, falls.len(), &wrong)
            );
        }
        if let Some(path) = self.junit {
            let cases: Vec<TestCase> = falls
                .iter()
                .map(|(name, c)| TestCase {
                    name: name.clone(),
                    classname: file.display().to_string(),
                    failure: (!self.holds(c.class)).then(|| {
                        format!(
                            "{name}: classified {} ({}), expected {}",
                            c.class,
                            c.regime,
                            self.either()
                        )
                    }),
                })
                .collect();
            let suite = format!("leafmagic classify {}", file.display());
            leafmagic::util::io::write_atomic(path, junit_xml(&suite, &cases).as_bytes())
                .with_context(|| format!("--junit: cannot write {}", path.display()))?;
        }
        if wrong.is_empty() {
            return Ok(());
        }
        let named: Vec<String> = wrong
            .iter()
            .map(|(name, c)| format!("`{name}` {} ({})", c.class, c.regime))
            .collect();
        bail!(
            "{}: {} of {} fall{} {} not {}: {}",
            file.display(),
            wrong.len(),
            falls.len(),
            if falls.len() == 1 { "" } else { "s" },
            if wrong.len() == 1 { "is" } else { "are" },
            self.either(),
            named.join(", ")
        )
    }
}

/// `classify --all`: every fall of an animation file, each classified as
/// `classify FILE --object NAME` classifies it ([`fall::classify_objects`]).
fn classify_all(args: &FallArgs, expectation: Option<&Expectation>) -> Result<()> {
    use leafmagic::formats::fall::{self, AnimationFormat};
    use leafmagic::motion::trajectory::UpAxis;
    let path = &args.trajectory;
    let Some(format) = AnimationFormat::of(path) else {
        bail!(
            "{}: --all classifies every fall of an animation file (.glb, .gltf, USD or Alembic); a CSV record holds one fall: leave --all out",
            path.display()
        );
    };
    if args.up != UpAxis::Z || args.frame_rate.is_some() {
        bail!(
            "{}: --up and --frame-rate apply to a CSV record; an animation file says its own up axis and rate",
            path.display()
        );
    }
    let alembic = format == AnimationFormat::Alembic;
    if args.scale != 1.0 && !alembic {
        bail!(
            "{}: --scale applies to a CSV record or an Alembic archive; glTF and USD say their own units",
            path.display()
        );
    }
    input::check_size(args.size)?;
    if !(args.scale > 0.0 && args.scale.is_finite()) {
        bail!(
            "--scale must be a positive number of metres per unit, got {}",
            args.scale
        );
    }
    let mut clip = fall::read_clip_in(path, args.animation.as_deref(), &args.reading.policy())?;
    for warning in &clip.warnings {
        eprintln!("warning: {}: {warning}", path.display());
    }
    if args.scale != 1.0 {
        clip.objects.iter_mut().for_each(|o| o.scale(args.scale));
    }
    let classes = fall::classify_objects(&clip, args.size, |_| true);
    if args.json {
        let objects: Vec<serde_json::Value> = clip
            .objects
            .iter()
            .zip(&classes)
            .filter_map(|(o, c)| {
                let c = c.as_ref()?;
                let (first, last) = o.life_s(clip.fps);
                let mut v = json!({
                    "object": o.name,
                    "first_s": first,
                    "last_s": last,
                    "class": c.class.as_str(),
                    "regime": c.regime.as_str(),
                    "inputs": c.inputs,
                    "reason": c.reason,
                });
                if let Some(e) = expectation {
                    v["as_expected"] = json!(e.holds(c.class));
                }
                Some(v)
            })
            .collect();
        let left_out: Vec<&str> = clip
            .objects
            .iter()
            .zip(&classes)
            .filter(|(_, c)| c.is_none())
            .map(|(o, _)| o.name.as_str())
            .collect();
        let mut out = json!({
            "file": path.display().to_string(),
            "rate_hz": clip.fps,
            "objects": objects,
            "left_out": left_out,
            "warnings": clip.warnings,
        });
        if let Some(e) = expectation {
            out["expected"] = json!(e.names());
        }
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        print!("{}", report::motion::classified_each(path, &clip, &classes));
    }
    match expectation {
        Some(e) => {
            let falls: Vec<(String, &Classification)> = clip
                .objects
                .iter()
                .zip(&classes)
                .filter_map(|(o, c)| Some((o.name.clone(), c.as_ref()?)))
                .collect();
            e.check(path, &falls, args.json)
        }
        None => Ok(()),
    }
}

/// What reading a fall noticed, as `classify --json` and `describe --json`
/// report it beside the classification (each field only where it applies).
#[derive(serde::Serialize)]
struct ReadingNotes<'a> {
    /// Columns of a CSV record that were not read.
    #[serde(skip_serializing_if = "<[String]>::is_empty")]
    ignored_columns: &'a [String],
    /// The horizontal column a one-camera record lacks.
    #[serde(skip_serializing_if = "Option::is_none")]
    depth_missing: Option<&'a str>,
    /// Rows left out for having no position.
    #[serde(skip_serializing_if = "Option::is_none")]
    lost_rows: Option<usize>,
    /// The object read from an animation file.
    #[serde(skip_serializing_if = "Option::is_none")]
    object: Option<&'a str>,
    /// The chord an animation file's fall was classified with, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    size_m: Option<f64>,
    /// What reading an animation file left out without refusing it.
    #[serde(skip_serializing_if = "<[String]>::is_empty")]
    warnings: &'a [String],
}

impl<'a> ReadingNotes<'a> {
    fn of(fall: &'a input::Fall) -> ReadingNotes<'a> {
        let notes = &fall.record.notes;
        ReadingNotes {
            ignored_columns: &notes.ignored_columns,
            depth_missing: notes.depth_missing.as_deref(),
            lost_rows: notes.lost_rows.map(|l| l.count),
            object: fall.record.object.as_deref(),
            size_m: fall.record.object.is_some().then_some(fall.size),
            warnings: &fall.record.warnings,
        }
    }
}

/// A fall's class, regime and measured descriptors as one JSON object (a
/// value without meaning, a period the fall does not have, as null).
fn descriptors_json(d: &Descriptors) -> serde_json::Value {
    let mut m = serde_json::Map::new();
    m.insert("class".into(), json!(d.class.as_str()));
    m.insert("regime".into(), json!(d.regime.as_str()));
    for (k, name) in describe::NAMES.iter().enumerate() {
        if !d.measured[k] {
            continue;
        }
        let v = d.values[k];
        m.insert(
            (*name).into(),
            if v.is_finite() { json!(v) } else { json!(null) },
        );
    }
    serde_json::Value::Object(m)
}

/// `describe`: one fall's descriptors, their units and scales, and which
/// of them the record could not give. An undetermined fall has none; that
/// is an answer (with its reason), not an error, as in `classify`.
pub fn describe(args: FallArgs) -> Result<()> {
    let fall = args.read()?;
    let (traj, c) = (&fall.record.trajectory, &fall.classification);
    let d = Descriptors::of(c).ok();
    if args.json {
        let not_measured: Vec<serde_json::Value> = match &d {
            Some(d) => (0..describe::NAMES.len())
                .filter(|&k| !d.measured[k])
                .map(|k| {
                    json!({ "name": describe::NAMES[k], "reason": describe::unmeasured_because(k) })
                })
                .collect(),
            None => Vec::new(),
        };
        let mut out = json!({
            "file": args.trajectory.display().to_string(),
            "samples": traj.len(),
            "class": c.class.as_str(),
            "regime": c.regime.as_str(),
            "reason": c.reason,
            "inputs": c.inputs,
            "descriptors": d.as_ref().map(descriptors_json),
            "not_measured": not_measured,
            "scales": describe::NAMES.iter().zip(describe::SCALES).map(|(n, s)| ((*n).to_string(), json!(s))).collect::<serde_json::Map<_, _>>(),
        });
        if let serde_json::Value::Object(noted) = serde_json::to_value(ReadingNotes::of(&fall))? {
            for (key, value) in noted {
                out[key] = value;
            }
        }
        if let Some(rest) = &c.at_rest {
            out["at_rest"] = json!(rest);
        }
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        print!(
            "{}",
            report::motion::described(&args.trajectory, traj.len(), c, d.as_ref())
        );
    }
    Ok(())
}

/// `compare`: two falls' descriptors side by side, and their distance.
pub fn compare(args: CompareArgs) -> Result<()> {
    let size = |pick: fn(EachFile<f64>) -> f64| args.size.map(pick);
    fn side(given: &Option<EachFile<String>>, k: usize) -> Option<&str> {
        given.as_ref().map(|EachFile(a, b)| [a, b][k].as_str())
    }
    let policy = args.reading.policy();
    let pick = |k: usize| input::Pick {
        object: side(&args.object, k),
        animation: side(&args.animation, k),
        policy: Some(&policy),
    };
    let [units_a, units_b] = args.units();
    let (_, a) = input::describe_fall(&args.a, size(|s| s.0), units_a, pick(0))?;
    let (_, b) = input::describe_fall(&args.b, size(|s| s.1), units_b, pick(1))?;
    let d = describe::distance(&a, &b);
    if args.json {
        let side = descriptors_json;
        let out = json!({
            "a": { "file": args.a.display().to_string(), "descriptors": side(&a) },
            "b": { "file": args.b.display().to_string(), "descriptors": side(&b) },
            "distance": if d.is_finite() { json!(d) } else { json!(null) },
            "same_class": a.class == b.class,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    print!(
        "{}",
        report::motion::comparison((&args.a, &a), (&args.b, &b), d)
    );
    Ok(())
}
