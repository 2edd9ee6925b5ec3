//! `classify` and `compare`: what a recorded fall shows, and how far apart
//! two falls are.

use super::args::{ClassifyArgs, CompareArgs};
use super::{input, report};
use anyhow::Result;
use leafmagic::motion::describe::{self, Descriptors};
use serde_json::json;

/// `classify`: names the motion of a recorded fall.
pub fn classify(args: ClassifyArgs) -> Result<()> {
    let (traj, notes, c) = input::classify_file(&args.trajectory, args.size, args.up)?;
    if args.json {
        // The classification's own fields in their order, then the notes.
        #[derive(serde::Serialize)]
        struct Noted<'a> {
            #[serde(flatten)]
            classification: &'a leafmagic::motion::classify::Classification,
            #[serde(skip_serializing_if = "<[String]>::is_empty")]
            ignored_columns: &'a [String],
        }
        let noted = Noted {
            classification: &c,
            ignored_columns: &notes.ignored_columns,
        };
        println!("{}", serde_json::to_string_pretty(&noted)?);
    } else {
        print!(
            "{}",
            report::motion::classified(&args.trajectory, traj.len(), &c)
        );
    }
    Ok(())
}

/// `compare`: two falls' descriptors side by side, and their distance.
pub fn compare(args: CompareArgs) -> Result<()> {
    let a = input::describe_file(&args.a, args.size, args.up)?;
    let b = input::describe_file(&args.b, args.size, args.up)?;
    let d = describe::distance(&a, &b);
    if args.json {
        let side = |d: &Descriptors| {
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
        };
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
