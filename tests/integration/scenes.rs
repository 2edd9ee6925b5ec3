//! The paper's seven scenes (scenes/*.toml) do what section 4.2 describes,
//! checked with numbers: each scene's test runs the shipped file.

use crate::common::V3;
use leafmagic::physics::field::{Flow, Uniform, WindField};
use leafmagic::physics::forces::Forces;
use leafmagic::physics::state::State;
use leafmagic::sim::scene::{ObjectKind, Scene, SceneObject};
use std::f64::consts::{PI, TAU};
use std::path::{Path, PathBuf};

pub fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(format!("{name}.toml"))
}

pub fn load(name: &str) -> Scene {
    Scene::load(&scene_path(name)).unwrap_or_else(|e| panic!("{e}"))
}

fn com(scene: &Scene, obj: &SceneObject, x: &[V3]) -> V3 {
    let (mut c, mut m) = (V3::zeros(), 0.0);
    for &i in &obj.particles {
        c += x[i] * scene.model.mass[i];
        m += scene.model.mass[i];
    }
    c / m
}

fn leaves(scene: &Scene) -> Vec<&SceneObject> {
    scene
        .objects
        .iter()
        .filter(|o| o.kind == ObjectKind::Leaf)
        .collect()
}

/// Every frame's positions (t, all particles).
fn record(scene: &Scene) -> Vec<(f64, Vec<V3>)> {
    let mut frames = Vec::new();
    scene
        .run_with(None, |_, s| frames.push((s.time, s.position.clone())))
        .unwrap_or_else(|e| panic!("{}: {e}", scene.name));
    frames
}

/// Hovering: the updraft cancels the fall, and leaves released outside the
/// hover volume (1.2 ≤ z ≤ 1.8, |x|, |y| ≤ 0.5) are brought back by the
/// bounding fields: from 4 s on every leaf stays within 3 cm of the height
/// band and inside the horizontal bounds, and over the last 2 s no leaf
/// drifts more than 1 cm vertically.
#[test]
fn hover_keeps_the_leaves_in_the_height_band() {
    let scene = load("hover");
    let frames = record(&scene);
    let leaves = leaves(&scene);
    let (band_lo, band_hi, margin) = (1.2, 1.8, 0.03);
    let outside = leaves
        .iter()
        .filter(|o| {
            let z = com(&scene, o, &frames[0].1).z;
            !(band_lo..=band_hi).contains(&z)
        })
        .count();
    assert!(outside >= 4, "only {outside} leaves start outside the band");
    let at = |t: f64| &frames.iter().find(|(ft, _)| *ft >= t - 1e-9).unwrap().1;
    for o in &leaves {
        for (t, x) in frames.iter().filter(|(t, _)| *t >= 4.0) {
            let c = com(&scene, o, x);
            assert!(
                c.z > band_lo - margin && c.z < band_hi + margin,
                "{} at z = {:.3} m at t = {t:.2} s",
                o.name,
                c.z
            );
            assert!(
                c.x.abs() < 0.6 && c.y.abs() < 0.6,
                "{} strayed to {c:?}",
                o.name
            );
        }
        let drift = (com(&scene, o, at(10.0)).z - com(&scene, o, at(8.0)).z).abs();
        assert!(drift < 0.01, "{} drifted {drift} m in the last 2 s", o.name);
    }
}

/// The shockwave moves leaves only after its front passes them: until the
/// first front's falloff band reaches a leaf, the leaf's particles are
/// bit-identical to a run without the shockwave; after it passes, the leaf
/// rears up at least 0.5 m within 1.5 s; at the end the second front has
/// driven every leaf to the ground, and none went through it.
#[test]
fn shockwave_moves_leaves_only_after_the_front_passes() {
    let path = scene_path("shockwave");
    let text = std::fs::read_to_string(&path).unwrap();
    let base = path.parent().unwrap();
    let scene = Scene::from_toml(&text, "shockwave.toml", base).unwrap();
    let mut spec: leafmagic::sim::scene::SceneSpec = toml::from_str(&text).unwrap();
    let fronts: Vec<_> = spec
        .wind
        .primitives()
        .iter()
        .filter(|p| p.front().is_some())
        .cloned()
        .collect();
    assert_eq!(fronts.len(), 2);
    let up = fronts
        .iter()
        .find(|p| matches!(p.flow(), Flow::Uniform(Uniform { velocity }) if velocity.z > 0.0))
        .unwrap()
        .front()
        .unwrap()
        .clone();
    spec.wind = WindField::new(
        spec.wind
            .primitives()
            .iter()
            .filter(|p| p.front().is_none())
            .cloned()
            .collect(),
    );
    let calm = Scene::from_spec(&spec, "shockwave without fronts", base).unwrap();
    let (with, without) = (record(&scene), record(&calm));
    let band_top = |t: f64| up.offset_at(t) + up.falloff;
    for o in leaves(&scene) {
        let lowest = |x: &[V3]| {
            o.particles
                .iter()
                .map(|&i| x[i].z)
                .fold(f64::INFINITY, f64::min)
        };
        let pass = with
            .iter()
            .position(|(t, x)| band_top(*t) >= lowest(x))
            .unwrap_or_else(|| panic!("the front never reached {}", o.name));
        assert!(with[pass].0 > 0.5, "{} was reached at once", o.name);
        for ((_, x), (_, y)) in with.iter().zip(&without).take(pass) {
            for &i in &o.particles {
                assert_eq!(x[i], y[i], "{} moved before the front reached it", o.name);
            }
        }
        let (t_pass, z_pass) = (with[pass].0, com(&scene, o, &with[pass].1).z);
        let peak = with
            .iter()
            .filter(|(t, _)| *t > t_pass && *t <= t_pass + 1.5)
            .map(|(_, x)| com(&scene, o, x).z)
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(
            peak > z_pass + 0.5,
            "{} rose only to {peak} from {z_pass}",
            o.name
        );
        let last = &with.last().unwrap().1;
        for &i in &o.particles {
            assert!(
                last[i].z < 0.05,
                "{} is not on the ground: z = {}",
                o.name,
                last[i].z
            );
        }
    }
    let lowest = with
        .iter()
        .flat_map(|(_, x)| x.iter().map(|p| p.z))
        .fold(f64::INFINITY, f64::min);
    assert!(
        lowest >= 0.0,
        "a particle went {lowest} m through the ground"
    );
}

/// Tilt (degrees) of a leaf's body z axis from the vertical.
fn tilt_deg(q: &nalgebra::UnitQuaternion<f64>) -> f64 {
    (q * V3::z()).z.clamp(-1.0, 1.0).acos().to_degrees()
}

/// Blown along the ground: at rest (static friction) until the wind rises
/// at 1 s, then every leaf tumbles over at least once and travels at least
/// 3 m downwind in 5 s, staying on the ground (centre below 10 cm, no
/// particle below it).
#[test]
fn ground_blow_tumbles_leaves_along_the_ground() {
    let scene = load("ground-blow");
    let run = scene.run(None).unwrap();
    for (o, obj) in scene.objects.iter().enumerate() {
        let traj = run.poses[o].as_ref().unwrap();
        let at = |t: f64| {
            let k = traj.time.iter().position(|&s| s >= t - 1e-9).unwrap();
            traj.position[k]
        };
        let settle = (at(0.95) - at(0.5)).xy().norm();
        assert!(
            settle < 1e-3,
            "{} slid {settle} m before the wind",
            obj.name
        );
        let travel = at(6.0) - at(1.0);
        assert!(
            travel.x > 3.0,
            "{} moved only {:.3} m downwind",
            obj.name,
            travel.x
        );
        assert!(
            travel.y.abs() < 0.2 * travel.x,
            "{} veered: {travel:?}",
            obj.name
        );
        let highest = traj
            .time
            .iter()
            .zip(&traj.position)
            .filter(|(t, _)| **t >= 1.0)
            .map(|(_, p)| p.z)
            .fold(0.0, f64::max);
        assert!(highest < 0.1, "{} flew up to {highest} m", obj.name);
        let max_tilt = traj.orientation.iter().map(tilt_deg).fold(0.0, f64::max);
        assert!(
            max_tilt > 90.0,
            "{} never turned over (max tilt {max_tilt:.0}°)",
            obj.name
        );
        let frames = run.particles[o].as_ref().unwrap();
        let lowest = frames
            .iter()
            .flatten()
            .map(|p| p.z)
            .fold(f64::INFINITY, f64::min);
        assert!(
            lowest >= 0.0,
            "{} went {lowest} m into the ground",
            obj.name
        );
    }
}

/// Inhaled: every leaf swirls at least half a turn about the bin's axis in
/// the vortex's sense, enters over the rim (its centre is above the rim when
/// it first comes within the bin's radius), and ends with every particle
/// inside the bin; the bin itself stays put.
#[test]
fn inhale_ends_with_every_leaf_inside_the_bin() {
    let scene = load("inhale");
    let (radius, height) = (0.3, 0.6);
    let frames = record(&scene);
    let bin = scene.object("bin").unwrap();
    for o in leaves(&scene) {
        let mut turns = 0.0;
        let mut prev: Option<f64> = None;
        let mut entry = None;
        for (t, x) in &frames {
            let c = com(&scene, o, x);
            let angle = c.y.atan2(c.x);
            if let Some(p) = prev {
                turns += ((angle - p + PI).rem_euclid(TAU) - PI) / TAU;
            }
            prev = Some(angle);
            if entry.is_none() && c.xy().norm() < radius {
                entry = Some((*t, c.z));
            }
        }
        assert!(turns > 0.5, "{} swirled only {turns:.2} turns", o.name);
        let (t, z) = entry.unwrap_or_else(|| panic!("{} never reached the bin", o.name));
        assert!(
            z > height,
            "{} came in through the wall at z = {z} (t = {t})",
            o.name
        );
        let last = &frames.last().unwrap().1;
        for &i in &o.particles {
            let p = last[i];
            assert!(
                p.xy().norm() < radius && (0.0..=height).contains(&p.z),
                "{} ends outside the bin: {p:?}",
                o.name
            );
        }
    }
    let moved =
        (com(&scene, bin, &frames.last().unwrap().1) - com(&scene, bin, &frames[0].1)).norm();
    assert!(moved < 1e-3, "the bin moved {moved} m");
}

/// Swings: the anchors never move; the gust pushes each seat at least 15 cm
/// downwind; once the wind has stopped each swing swings at the period of
/// the compound pendulum formed by its seat and ropes about the line
/// through its anchors, T = 2π √(I / (g Σ mᵢ hᵢ)), within 1.5 %.
#[test]
fn swings_sway_in_the_gust_and_swing_at_the_pendulum_period() {
    let scene = load("swings");
    let frames = record(&scene);
    let g = scene.model.gravity.norm();
    for (_, x) in &frames {
        for o in scene.objects.iter().filter(|o| o.kind == ObjectKind::Fixed) {
            let i = o.particles[0];
            assert_eq!(x[i], scene.model.rest_position[i], "{} moved", o.name);
        }
    }
    for n in 1..=2 {
        let seat = scene.object(&format!("seat-{n}")).unwrap();
        let anchor = scene.object(&format!("beam-{n}l")).unwrap().particles[0];
        let pivot = scene.model.rest_position[anchor];
        // The swinging parts: the seat and the ropes' own particles (not their ends).
        let mut parts: Vec<usize> = seat.particles.clone();
        for rope in scene
            .objects
            .iter()
            .filter(|o| o.kind == ObjectKind::Rope && o.name.starts_with(&format!("rope-{n}")))
        {
            parts.extend(&rope.particles[1..rope.particles.len() - 1]);
        }
        let (mut inertia, mut moment) = (0.0, 0.0);
        for &i in &parts {
            let (m, r) = (scene.model.mass[i], scene.model.rest_position[i] - pivot);
            inertia += m * (r.x * r.x + r.z * r.z);
            moment += m * -r.z;
        }
        let period = TAU * (inertia / (g * moment)).sqrt();
        let x: Vec<(f64, f64)> = frames
            .iter()
            .map(|(t, p)| (*t, com(&scene, seat, p).x))
            .collect();
        let sway = x
            .iter()
            .filter(|(t, _)| (1.0..=8.0).contains(t))
            .map(|(_, v)| *v)
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(sway > 0.15, "seat-{n} swayed only {sway} m");
        let free: Vec<_> = x.iter().filter(|(t, _)| *t >= 9.0).collect();
        let mean = free.iter().map(|(_, v)| v).sum::<f64>() / free.len() as f64;
        let ups: Vec<f64> = free
            .windows(2)
            .filter(|w| w[0].1 < mean && w[1].1 >= mean)
            .map(|w| w[0].0 + (mean - w[0].1) / (w[1].1 - w[0].1) * (w[1].0 - w[0].0))
            .collect();
        assert!(ups.len() >= 3, "seat-{n}: too few swings ({})", ups.len());
        let measured = (ups[ups.len() - 1] - ups[0]) / (ups.len() - 1) as f64;
        assert!(
            (measured - period).abs() < 0.015 * period,
            "seat-{n}: period {measured:.4} s, compound pendulum {period:.4} s"
        );
    }
}

/// The rocking bin: knocked onto its front rim by the skid, it rocks back
/// and forth (tilt above 10°, at least three changes of side) and comes to
/// rest upright, its kinetic energy below 1e-6 of its peak, never sinking
/// into the ground.
#[test]
fn rocking_bin_rocks_to_a_stop() {
    let scene = load("rocking-bin");
    let body = &scene.model.rigid[0];
    let bin = scene.object("bin").unwrap();
    let mut tracker = leafmagic::physics::pose::PoseTracker::new(
        &bin.pose.as_ref().unwrap().model,
        bin.pose.as_ref().unwrap().initial,
    );
    let (mut peak, mut last_ke) = (0.0f64, 0.0);
    let (mut max_tilt, mut sides, mut side) = (0.0f64, 0, 0.0f64);
    let (mut lowest, mut last_tilt) = (f64::INFINITY, 0.0);
    let mut scratch = Vec::new();
    scene
        .run_with(None, |_, s: &State| {
            let ke = body.kinetic_energy(&s.position, &s.velocity);
            peak = peak.max(ke);
            last_ke = ke;
            scratch.clear();
            scratch.extend(bin.particles.iter().map(|&i| s.position[i]));
            let (_, q) = tracker.pose(&bin.pose.as_ref().unwrap().model, &scratch);
            let axis = q * V3::z();
            // Signed tilt in the x-z plane (the skid is along +x).
            let tilt = axis.x.atan2(axis.z).to_degrees();
            max_tilt = max_tilt.max(tilt.abs());
            if tilt.abs() > 0.5 && tilt.signum() != side {
                sides += 1;
                side = tilt.signum();
            }
            last_tilt = tilt;
            lowest = s.position.iter().map(|p| p.z).fold(lowest, f64::min);
        })
        .unwrap();
    assert!(max_tilt > 10.0, "it tipped only {max_tilt:.1}°");
    assert!(sides >= 4, "it rocked to {sides} sides");
    assert!(last_tilt.abs() < 0.1, "it ends tilted {last_tilt:.3}°");
    assert!(
        last_ke < 1e-6 * peak,
        "kinetic energy {last_ke:e} J of a {peak:e} J peak"
    );
    assert!(lowest > -1e-3, "it sank {lowest} m into the ground");
}

/// The tear: nothing breaks before the gust; at least 50 springs break
/// during it; a broken spring stays broken; and after breaking nothing acts
/// through it: the force on every particle equals, bit for bit, that of the
/// model with the broken springs and torn triangles removed. The torn sheet
/// is carried downwind.
#[test]
fn tear_breaks_springs_that_then_act_no_more() {
    let scene = load("tear");
    let gust = 1.0;
    let mut alive_prev = scene.initial.spring_alive.clone();
    let mut final_state = None;
    scene
        .run_with(None, |_, s| {
            for (was, &is) in alive_prev.iter().zip(&s.spring_alive) {
                assert!(*was || !is, "a broken spring came back at t = {}", s.time);
            }
            if s.time <= gust {
                assert_eq!(s.broken_springs(), 0, "a spring broke before the gust");
            }
            alive_prev.clone_from(&s.spring_alive);
            final_state = Some(s.clone());
        })
        .unwrap();
    let s = final_state.unwrap();
    assert!(
        s.broken_springs() >= 50,
        "only {} springs broke",
        s.broken_springs()
    );

    let mut forces = Forces::new(&scene.model);
    forces.tear(&s.spring_alive);
    let mut total = vec![V3::zeros(); s.position.len()];
    forces.total(
        &scene.model,
        &s.position,
        &s.velocity,
        &s.spring_alive,
        s.time,
        &mut total,
    );
    let mut intact = scene.model.clone();
    let torn: Vec<bool> = forces.torn().triangles.clone();
    intact.springs = scene
        .model
        .springs
        .iter()
        .zip(&s.spring_alive)
        .filter(|(_, a)| **a)
        .map(|(sp, _)| *sp)
        .collect();
    intact.triangles = scene
        .model
        .triangles
        .iter()
        .zip(&torn)
        .filter(|(_, t)| !**t)
        .map(|(tri, _)| *tri)
        .collect();
    assert!(intact.triangles.len() < scene.model.triangles.len());
    let mut expected = vec![V3::zeros(); s.position.len()];
    Forces::new(&intact).total(
        &intact,
        &s.position,
        &s.velocity,
        &vec![true; intact.springs.len()],
        s.time,
        &mut expected,
    );
    assert_eq!(
        total, expected,
        "a broken spring or torn triangle still acts"
    );

    let sheet = scene.object("sheet").unwrap();
    let free: Vec<usize> = sheet
        .particles
        .iter()
        .copied()
        .filter(|&i| !scene.model.fixed[i])
        .collect();
    let carried = free.iter().map(|&i| s.position[i].y).sum::<f64>() / free.len() as f64;
    assert!(
        carried > 0.5,
        "the torn sheet moved only {carried} m downwind"
    );
}
