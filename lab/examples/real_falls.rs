//! The real-falls experiment (Howison, Hughes & Iida 2020) in leafmagic:
//! paper squares of each size bin's median side, 70 g/m², released flat
//! and on edge, filmed and labelled as the experiment did, side by side
//! with the real falls in tests/data/real-falls/squares (docs/lab/real-falls.md),
//! then the real side's bootstrap intervals with the simulated values that
//! lie outside them marked.
//! With `--shape circle|hexagon`, plates of that shape at
//! the squares' bin sizes: the simulated side only, a prediction for the
//! study's held-out shapes (docs/lab/real-falls.md, "Predictions for the
//! held-out shapes"). `--films DIR` compares with the films in DIR instead
//! of the squares, in the squares' format (`real_falls::read_films`), with
//! plates of the films' own shape: the held-out shapes' check, once their
//! films are given.
//! A third table splits each bin by release (flat, on edge): the pooled
//! medians mix the two in each side's own proportion. `--mix filmed` lets
//! each bin go flat and on edge in its real proportion instead of half and
//! half, `--flat-tilt LO,HI` tilts flat releases LO–HI° instead of 1–5°
//! (docs/lab/real-falls.md, "The release protocol"); that table also times when
//! each flat release departs from its flat fall ("When a flat release
//! departs"). A line under it gives the like-for-like mismatch: each kind
//! of release's median drift and Ω against the films' own of that kind
//! (`real_falls::release_mismatch`; "Munk relief near broadside"). The
//! next table re-weights the films to the simulated bins' share of flat
//! releases (`real_falls::real_table_at_mix`) and compares like for like,
//! and a line lists the statistics outside issue 17's per-bin bounds
//! against both ("The films at the simulated mix"). The
//! last table gives each release's fastest descent beside the simulated
//! plate's steady edge-on fall ("How fast real paper dives") and how far
//! its path turns from the first third of its fall to the last ("How far
//! a tumbling path turns"). `--bending D` cuts the squares from paper that
//! bends, of bending stiffness D N·m, instead of rigid plates (`plates::
//! flexible`; "Paper that bends, and a draught in the room"): minutes, not
//! a second. `--refine N` meshes the plates N times finer across ("Is the
//! experiment converged?"). `--draught SPEED,TIME` lets each release fall
//! in its own random draught ("Paper that bends, and a draught in the
//! room"). `--shape cross --cross-arm R` cuts crosses of span the bin's
//! size and arms R × the span wide (the study's fourth shape, "Predictions
//! for the held-out shapes").
//!
//! cargo run --release --example real_falls [-- --releases N --seed S --law NAME --shape NAME --films DIR --mix halves|filmed --flat-tilt LO,HI --bending N_M --refine N --draught SPEED,TIME --cross-arm R KEY=VALUE ...]

use leafmagic::leaf::plates::{PlateShape, plate};
use leafmagic::leaf::{AeroLawName, AeroSpec};
use leafmagic::physics::aero::unsteady;
use leafmagic::physics::model::AeroLaw;
use leafmagic_lab::real_falls::{self, BinStats, Protocol, ReleaseStats};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// What the example takes.
const USAGE: &str = "usage: cargo run --release --example real_falls -- [--releases N] [--seed S] [--law NAME] [--shape square|circle|hexagon|rectangle|cross] [--films DIR] [--mix halves|filmed] [--flat-tilt LO,HI] [--bending N_M] [--refine N] [--draught SPEED,TIME] [--cross-arm W/S] [KEY=VALUE ...]\n  KEY=VALUE: any [aero] key of the law (docs/lab/real-falls.md, \"The law\")";

/// Resamples of the real side's bootstrap: the 5th and 95th percentiles of
/// 2,000 move by less than the printed digits between seeds.
const BOOTSTRAP_RESAMPLES: usize = 2000;

fn main() -> ExitCode {
    leafmagic::util::pipe::quiet_broken_pipe();
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("real_falls: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The value after flag `flag`, parsed, or an error naming the flag, what
/// it wants and what it got.
fn value<T: std::str::FromStr>(
    args: &mut impl Iterator<Item = String>,
    flag: &str,
    wants: &str,
) -> Result<T, String>
where
    T::Err: std::fmt::Display,
{
    let v = args
        .next()
        .ok_or_else(|| format!("{flag}: missing value ({wants})"))?;
    v.parse()
        .map_err(|e| format!("{flag}: {v:?} is not {wants}: {e}"))
}

/// The two numbers `A,B` after flag `flag`, or an error naming the flag,
/// what it wants and what it got.
fn pair(
    args: &mut impl Iterator<Item = String>,
    flag: &str,
    wants: &str,
) -> Result<[f64; 2], String> {
    let v: String = value(args, flag, wants)?;
    let parts = v
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| format!("{flag}: {v:?} is not {wants}: {e}"))?;
    match parts[..] {
        [a, b] => Ok([a, b]),
        _ => Err(format!("{flag}: {v:?} is not two numbers ({wants})")),
    }
}

fn run() -> Result<(), String> {
    let mut releases: usize = 12;
    let mut seed: u64 = 1;
    let mut shape: Option<PlateShape> = None;
    let mut films: Option<PathBuf> = None;
    let mut aero = AeroSpec::unsteady();
    let mut protocol = Protocol::default();
    let mut args = std::env::args().skip(1);
    let mut extra = Vec::new();
    while let Some(a) = args.next() {
        match a.as_str() {
            "--releases" => releases = value(&mut args, "--releases", "a count")?,
            "--seed" => seed = value(&mut args, "--seed", "a whole number")?,
            "--shape" => {
                shape = Some(value(
                    &mut args,
                    "--shape",
                    "square, circle, hexagon, rectangle or cross",
                )?)
            }
            "--films" => films = Some(value(&mut args, "--films", "a folder of films")?),
            "--law" => {
                let law: AeroLawName = value(&mut args, "--law", "a law's name")?;
                aero = if law == AeroLawName::Linear {
                    AeroSpec::linear(0.47, 0.047)
                } else {
                    AeroSpec::named(law)
                };
            }
            "--mix" => protocol.mix = value(&mut args, "--mix", "halves or filmed")?,
            "--flat-tilt" => {
                protocol.flat_tilt_deg = pair(&mut args, "--flat-tilt", "LO,HI in degrees")?;
                protocol.check().map_err(|e| format!("--flat-tilt: {e}"))?;
            }
            "--bending" => {
                let d: f64 = value(&mut args, "--bending", "a bending stiffness in N·m")?;
                protocol.bending = Some(d);
                protocol.check().map_err(|e| format!("--bending: {e}"))?;
            }
            "--draught" => {
                let [speed, correlation] = pair(&mut args, "--draught", "SPEED,TIME in m/s and s")?;
                protocol.draught = Some(real_falls::Draught { speed, correlation });
                protocol.check().map_err(|e| format!("--draught: {e}"))?;
            }
            "--cross-arm" => {
                let r: f64 = value(&mut args, "--cross-arm", "an arm width over span")?;
                protocol.cross_arm = Some(r);
                protocol.check().map_err(|e| format!("--cross-arm: {e}"))?;
            }
            "--refine" => {
                protocol.refine = value(&mut args, "--refine", "a whole number >= 1")?;
                protocol.check().map_err(|e| format!("--refine: {e}"))?;
            }
            "-h" | "--help" => {
                println!("{USAGE}");
                return Ok(());
            }
            flag if flag.starts_with("--") => {
                return Err(format!("unknown flag {flag}\n{USAGE}"));
            }
            kv if kv.contains('=') => extra.push(kv.to_string()),
            other => {
                return Err(format!(
                    "{other:?} is neither a flag nor an [aero] KEY=VALUE\n{USAGE}"
                ));
            }
        }
    }
    if releases == 0 {
        return Err("--releases: must be at least 1".into());
    }
    let aero = aero
        .with_lines(&extra)
        .map_err(|e| format!("bad [aero] key: {e}"))?;
    let real = match &films {
        Some(dir) => real_falls::read_films(dir, None).map_err(|e| e.to_string())?,
        None => {
            let dir =
                Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/real-falls/squares");
            real_falls::read_squares(&dir).map_err(|e| e.to_string())?
        }
    };
    // The films' shape is the plates' (`compare_with`).
    let filmed = real_falls::films_shape(&real).map_err(|e| e.to_string())?;
    // What the first column holds: a square's side, another shape's size
    // as `leafmagic plate --size` takes it.
    let size_col = if filmed == PlateShape::Square {
        "side cm"
    } else {
        "size cm"
    };
    match (shape, &films) {
        (Some(shape), None) if shape != PlateShape::Square => {
            return predict(shape, &real, &aero, releases, seed, &protocol);
        }
        (Some(shape), Some(dir)) if shape != filmed => {
            return Err(format!(
                "--shape {} but the films in {} are {}s: the plates are cut to the films' shape",
                shape.as_str(),
                dir.display(),
                filmed.as_str()
            ));
        }
        _ => {}
    }
    let t0 = std::time::Instant::now();
    // A law whose keys pass one by one can still be refused as a whole
    // (translational lift above half the normal drag): say which.
    let cmp = real_falls::compare_with(&real, &aero, releases, seed, &protocol)
        .map_err(|e| format!("the experiment cannot run: {e}"))?;
    let wall = t0.elapsed().as_secs_f64();
    let law = toml::to_string(&real_falls::experiment_air(aero.clone()))
        .map_err(|e| format!("the law cannot be written: {e}"))?
        .replace('\n', " ");
    println!(
        "real falls of 70 g/m² paper {}s against leafmagic plates ({releases} releases per bin, seed {seed}; [aero] {law})",
        filmed.as_str()
    );
    print_protocol(&protocol);
    println!();
    println!(
        "{:<9} {:>12} {:>12} {:>15} {:>15} {:>15} {:>15} {:>6}",
        size_col,
        "real T:C:S",
        "sim T:C:S",
        "fT real/sim",
        "v m/s real/sim",
        "drift real/sim",
        "Ω rad/s r/s",
        "score"
    );
    let cell = |r: f64, s: f64, d: usize| format!("{r:.d$} / {s:.d$}");
    let counts = |b: &BinStats| format!("{}:{}:{}", b.counts[0], b.counts[1], b.counts[2]);
    for ((r, s), p) in cmp.real.iter().zip(&cmp.sim).zip(&cmp.parts) {
        println!(
            "{:<9.1} {:>12} {:>12} {:>15} {:>15} {:>15} {:>15} {:>6.2}",
            r.side * 100.0,
            counts(r),
            counts(s),
            cell(r.tumbling, s.tumbling, 2),
            cell(r.descent, s.descent, 3),
            cell(r.drift, s.drift, 2),
            cell(r.omega, s.omega, 1),
            p.iter().sum::<f64>()
        );
    }
    println!();
    println!(
        "the real side's {:.0} % bootstrap intervals ({BOOTSTRAP_RESAMPLES} resamples of each bin's tumbling and chaotic drops); * the simulated value lies outside",
        real_falls::BOOTSTRAP_LEVEL * 100.0
    );
    println!();
    println!(
        "{:<9} {:>13} {:>15} {:>13} {:>13}",
        size_col, "fT", "v m/s", "drift", "Ω rad/s"
    );
    let intervals = real_falls::real_intervals(&real, BOOTSTRAP_RESAMPLES, seed);
    for ((r, s), i) in cmp.real.iter().zip(&cmp.sim).zip(&intervals) {
        let inside = i.contains(s);
        let span = |[lo, hi]: [f64; 2], d: usize, ok: bool| {
            format!("{lo:.d$}–{hi:.d$}{}", if ok { " " } else { "*" })
        };
        println!(
            "{:<9.1} {:>13} {:>15} {:>13} {:>13}",
            r.side * 100.0,
            span(i.tumbling, 2, inside[0]),
            span(i.descent, 3, inside[1]),
            span(i.drift, 2, inside[2]),
            span(i.omega, 1, inside[3]),
        );
    }
    println!();
    println!(
        "by release (real / sim): drops, median drift, Ω rad/s, and when a flat release departs from its flat fall (median s, of how many; the films' past their first frames)"
    );
    println!();
    println!(
        "{:<9} {:>7} {:>11} {:>13} {:>19}   {:>7} {:>11} {:>13}",
        size_col, "flat", "drift", "Ω", "departs s", "edge", "drift", "Ω"
    );
    let by_real = real_falls::real_by_release(&real);
    let mut mismatch: [Vec<f64>; 4] = Default::default();
    for ((r, drops), br) in cmp.real.iter().zip(&cmp.drops).zip(&by_real) {
        let bs = real_falls::sim_by_release(drops);
        for (all, part) in mismatch
            .iter_mut()
            .zip(real_falls::release_mismatch(br, &bs))
        {
            all.extend(part);
        }
        let side = |a: &ReleaseStats, b: &ReleaseStats| {
            (
                format!("{}/{}", a.drops, b.drops),
                format!("{:.2}/{:.2}", a.drift, b.drift),
                format!("{:.1}/{:.1}", a.omega, b.omega),
            )
        };
        let (fd, fdr, fo) = side(&br.flat, &bs.flat);
        let (ed, edr, eo) = side(&br.edge, &bs.edge);
        let departs = format!(
            "{:.3}({})/{:.3}({})",
            br.flat.departs, br.flat.departs_drops, bs.flat.departs, bs.flat.departs_drops
        );
        println!(
            "{:<9.1} {fd:>7} {fdr:>11} {fo:>13} {departs:>19}   {ed:>7} {edr:>11} {eo:>13}",
            r.side * 100.0
        );
    }
    let average = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    println!();
    println!(
        "like for like, each release against the films' own (mean over bins of |ln sim/real|): flat drift {:.2}, flat Ω {:.2}, edge drift {:.2}, edge Ω {:.2}; sum {:.2}",
        average(&mismatch[0]),
        average(&mismatch[1]),
        average(&mismatch[2]),
        average(&mismatch[3]),
        mismatch.iter().map(|m| average(m)).sum::<f64>()
    );
    // The pooled medians mix the two kinds of release in each side's own
    // proportion: the films re-weighted to the simulated bins' mix compare
    // like for like.
    let sim_shares = cmp.sim_flat_shares();
    let film_shares = real_falls::real_flat_share(&real);
    let remixed = cmp.films_at_simulated_mix(&real);
    println!();
    println!(
        "the films at the simulated mix: each bin's real drops re-weighted to the simulated share of flat releases among its moving drops"
    );
    println!();
    println!(
        "{:<9} {:>13} {:>15} {:>15} {:>15} {:>15} {:>6}",
        size_col,
        "flat real→sim",
        "fT real/sim",
        "v m/s real/sim",
        "drift real/sim",
        "Ω rad/s r/s",
        "score"
    );
    for (((r, s), film), share) in remixed
        .iter()
        .zip(&cmp.sim)
        .zip(&film_shares)
        .zip(&sim_shares)
    {
        println!(
            "{:<9.1} {:>13} {:>15} {:>15} {:>15} {:>15} {:>6.2}",
            r.side * 100.0,
            format!("{film:.2}→{share:.2}"),
            cell(r.tumbling, s.tumbling, 2),
            cell(r.descent, s.descent, 3),
            cell(r.drift, s.drift, 2),
            cell(r.omega, s.omega, 1),
            real_falls::bin_score(r, s).iter().sum::<f64>()
        );
    }
    let missed = |real: &[BinStats]| {
        let all: Vec<String> = real
            .iter()
            .zip(&cmp.sim)
            .flat_map(|(r, s)| {
                real_falls::bounds_missed(r, s)
                    .into_iter()
                    .map(move |(name, q)| format!("{:.1} cm {name} {q:.2}", r.side * 100.0))
            })
            .collect();
        if all.is_empty() {
            "none".to_string()
        } else {
            all.join(", ")
        }
    };
    println!();
    println!(
        "score at the simulated mix {:.2}; per-bin bounds (v {:.0} %, drift ×{}, Ω {:.0} %) missed at the films' mix: {}; at the simulated mix: {}",
        cmp.score_against(&remixed),
        real_falls::DESCENT_BOUND * 100.0,
        real_falls::DRIFT_FACTOR,
        real_falls::OMEGA_BOUND * 100.0,
        missed(&cmp.real),
        missed(&remixed)
    );
    println!();
    println!(
        "fastest descent over a moving segment (median m/s, real / sim), the simulated plate's steady edge-on fall, and how far the path turns from the first third of the moving segment to the last (median |°|, real / sim)"
    );
    println!();
    println!(
        "{:<9} {:>11} {:>11} {:>9}   {:>11} {:>11}",
        size_col, "flat", "edge", "edge-on", "turn flat", "turn edge"
    );
    for ((r, drops), br) in cmp.real.iter().zip(&cmp.drops).zip(&by_real) {
        let bs = real_falls::sim_by_release(drops);
        let pair = |a: f64, b: f64| format!("{a:.2}/{b:.2}");
        let edge_on = edge_on_speed(filmed, r.side, protocol.plate_aspect(filmed), &aero)
            .map_or_else(|| "-".to_string(), |v| format!("{v:.2}"));
        let turn = |a: f64, b: f64| format!("{a:.0}/{b:.0}");
        println!(
            "{:<9.1} {:>11} {:>11} {edge_on:>9}   {:>11} {:>11}",
            r.side * 100.0,
            pair(br.flat.fastest, bs.flat.fastest),
            pair(br.edge.fastest, bs.edge.fastest),
            turn(br.flat.turn, bs.flat.turn),
            turn(br.edge.turn, bs.edge.turn),
        );
    }
    println!();
    println!(
        "what the simulated falls did, read from the plate's rotation over the filmed fall (T tumbling: turned over, never back; F fluttering: swung back, never over; M mixed: both; S neither), and how many of the tumbling falls the experiment's rule labels chaotic"
    );
    println!();
    println!(
        "{:<9} {:>12} {:>12}   {:>22}",
        size_col, "flat T:F:M:S", "edge T:F:M:S", "tumbling called chaotic"
    );
    for (r, drops) in cmp.real.iter().zip(&cmp.drops) {
        let counts = |on_edge| {
            let [t, f, m, st] = real_falls::rotation_counts(drops, on_edge);
            format!("{t}:{f}:{m}:{st}")
        };
        let tumbling: Vec<_> = drops
            .iter()
            .filter(|d| d.rotation == real_falls::Rotation::Tumbling)
            .filter_map(|d| d.moving_label())
            .collect();
        let chaotic = tumbling
            .iter()
            .filter(|&&l| l == real_falls::Label::Chaotic)
            .count();
        println!(
            "{:<9.1} {:>12} {:>12}   {:>22}",
            r.side * 100.0,
            counts(false),
            counts(true),
            format!("{chaotic} of {}", tumbling.len())
        );
    }
    let mean = |k: usize| cmp.parts.iter().map(|p| p[k]).sum::<f64>() / cmp.parts.len() as f64;
    println!();
    println!(
        "score {:.2} = fT {:.2} + v {:.2} + drift {:.2} + Ω {:.2} (mean over {} bins; {:.1} s wall)",
        cmp.score(),
        mean(0),
        mean(1),
        mean(2),
        mean(3),
        cmp.parts.len(),
        wall
    );
    Ok(())
}

/// The steady edge-on fall of the simulated plate of `shape`, `side` and
/// `aspect`
/// in the experiment's air under the unsteady law
/// ([`unsteady::edge_on_speed`]), m/s; `None` under another law.
fn edge_on_speed(shape: PlateShape, side: f64, aspect: f64, aero: &AeroSpec) -> Option<f64> {
    let spec = plate(
        shape,
        side,
        aspect,
        real_falls::PAPER,
        real_falls::experiment_air(aero.clone()),
    )
    .ok()?;
    let model = spec.model().ok()?;
    match &model.aero {
        AeroLaw::Unsteady(law) => Some(unsteady::edge_on_speed(law, &model)),
        _ => None,
    }
}

/// The lines that say how the plates were let go, meshed and cut, and in
/// what air.
fn print_protocol(protocol: &Protocol) {
    println!(
        "released {}, flat ones tilted {}–{}°",
        match protocol.mix {
            real_falls::ReleaseMix::Halves => "half flat, half on edge",
            real_falls::ReleaseMix::AsFilmed => "flat and on edge in each bin's real proportion",
        },
        protocol.flat_tilt_deg[0],
        protocol.flat_tilt_deg[1]
    );
    if protocol.refine != 1 {
        println!(
            "plates meshed {} times finer across than `leafmagic plate`'s",
            protocol.refine
        );
    }
    if let Some(d) = protocol.draught {
        println!(
            "a draught in the room: each horizontal component {} m/s r.m.s., correlated over {} s (real_falls::draught_field)",
            d.speed, d.correlation
        );
    }
    if let Some(r) = protocol.cross_arm {
        println!("crosses' arms {r} of their span wide");
    }
    if let Some(d) = protocol.bending {
        println!("plates that bend: paper of bending stiffness {d:.2e} N·m (plates::flexible)");
    }
}

/// The simulated side alone for plates of `shape` at the squares' bin sizes,
/// let go as `protocol` says.
fn predict(
    shape: PlateShape,
    real: &[real_falls::RealSegment],
    aero: &AeroSpec,
    releases: usize,
    seed: u64,
    protocol: &Protocol,
) -> Result<(), String> {
    let t0 = std::time::Instant::now();
    let sim = real_falls::predict(shape, real, aero, releases, seed, protocol)
        .map_err(|e| format!("the experiment cannot run: {e}"))?;
    let wall = t0.elapsed().as_secs_f64();
    println!(
        "{} plates of 70 g/m² paper at the squares' bin sizes, simulated only ({releases} releases per bin, seed {seed}); the real falls of this shape are held back",
        shape.as_str()
    );
    print_protocol(protocol);
    println!();
    println!(
        "{:<9} {:>12} {:>8} {:>8} {:>8} {:>9}",
        "size cm", "sim T:C:S", "fT", "v m/s", "drift", "Ω rad/s"
    );
    for s in &sim {
        println!(
            "{:<9.1} {:>12} {:>8.2} {:>8.3} {:>8.2} {:>9.1}",
            s.side * 100.0,
            format!("{}:{}:{}", s.counts[0], s.counts[1], s.counts[2]),
            s.tumbling,
            s.descent,
            s.drift,
            s.omega
        );
    }
    println!();
    println!("{:.1} s wall", wall);
    Ok(())
}
