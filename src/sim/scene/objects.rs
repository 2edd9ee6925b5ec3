//! Placing each kind of object a scene file lists into the builder, its
//! table's fields checked first: leaves (their copies scattered by a
//! SplitMix64 stream, so layouts never change with a crate upgrade), rigid
//! shapes, sheets and ropes hung between objects placed before them.

use super::builder::Builder;
use super::compiled::{ObjectKind, PoseFrame};
use super::error::{Ctx, SceneError, check_name};
use super::shapes::{self, Part};
use super::spec::{LeafObject, Pin, RigidObject, RopeObject, Shape, SheetObject};
use crate::leaf::LeafSpec;
use crate::physics::model::{Model, ModelParts, Spring, Triangle};
use nalgebra::{Unit, UnitQuaternion, Vector3};
use std::collections::HashMap;

type V3 = Vector3<f64>;

/// Rotation about x, then y, then z (fixed axes), from degrees.
fn rotation_xyz(deg: [f64; 3]) -> UnitQuaternion<f64> {
    let [x, y, z] = deg.map(f64::to_radians);
    UnitQuaternion::from_axis_angle(&V3::z_axis(), z)
        * UnitQuaternion::from_axis_angle(&V3::y_axis(), y)
        * UnitQuaternion::from_axis_angle(&V3::x_axis(), x)
}

/// SplitMix64: a tiny, fully specified generator, so that copies are placed
/// identically whatever version of any random-number crate is in use.
pub(super) struct SplitMix(pub(super) u64);

impl SplitMix {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
    /// Uniform in [−1, 1).
    fn signed(&mut self) -> f64 {
        2.0 * self.unit() - 1.0
    }
}

pub(super) fn add_leaf(
    ctx: &Ctx<'_>,
    b: &mut Builder,
    names: &mut HashMap<String, String>,
    rng: &mut SplitMix,
    k: usize,
    obj: &LeafObject,
) -> Result<(), SceneError> {
    let path = format!("leaf[{k}]");
    let field = |f: &str| format!("{path}.{f}");
    let (spec, leaf) = checked_leaf(ctx, &path, obj)?;
    one_law(ctx, b, &path, obj, &leaf)?;
    // A leaf file that is one rigid body (`rigid = true`: every plate of
    // `leafmagic plate`, which has no springs) stays one unless the scene
    // says otherwise; its particles would otherwise fly apart.
    let rigid = obj.rigid.unwrap_or(spec.rigid);
    let com = leaf.centre_of_mass(&leaf.rest_position);
    let part = Part {
        mass: leaf.mass.clone(),
        position: leaf.rest_position.clone(),
        fixed: leaf.fixed.clone(),
        ..Default::default()
    };
    if leaf.fixed.iter().any(|&f| f) && rigid {
        return Err(ctx.err(
            field("rigid"),
            "a leaf with fixed particles cannot be rigid",
        ));
    }
    let copies = obj.count as f64;
    b.reserve(
        ctx,
        &field("count"),
        &format!(
            "count = {} copies of a leaf of {} particles",
            obj.count,
            leaf.len()
        ),
        copies * leaf.len() as f64,
        if rigid {
            0.0
        } else {
            copies * leaf.springs.len() as f64
        },
    )?;
    let base = rotation_xyz(obj.rotation_deg);
    for copy in 0..obj.count {
        let name = if obj.count == 1 {
            obj.name.clone()
        } else {
            format!("{}-{copy:03}", obj.name)
        };
        check_name(ctx, &field("name"), &name, names)?;
        let (offset, rotation) = release(obj, rng, base);
        let start = b.parts.mass.len();
        let ids = b.add_part(
            &path,
            &part,
            &leaf.particle_drag,
            (0.0, 0.0),
            com,
            rotation,
            V3::from(obj.position) + offset,
            V3::from(obj.velocity),
            V3::from(obj.angular_velocity),
        );
        add_elements(b, &path, obj, &leaf, start, rigid, copy == 0);
        let pose = PoseFrame {
            model: leaf.clone(),
            initial: rotation,
        };
        b.push_object(name, ObjectKind::Leaf, ids, Some(pose), rigid, &path);
        b.set_surface(leaf.triangles.iter().map(|t| t.corners).collect());
    }
    Ok(())
}

/// A `[[leaf]]` table's numbers checked, and its leaf file read (under
/// the scene's law, if it sets one) and made a model.
fn checked_leaf(
    ctx: &Ctx<'_>,
    path: &str,
    obj: &LeafObject,
) -> Result<(LeafSpec, Model), SceneError> {
    let field = |f: &str| format!("{path}.{f}");
    ctx.vector(&field("position"), &obj.position)?;
    ctx.vector(&field("rotation_deg"), &obj.rotation_deg)?;
    ctx.vector(&field("velocity"), &obj.velocity)?;
    ctx.vector(&field("angular_velocity"), &obj.angular_velocity)?;
    ctx.vector(&field("spread"), &obj.spread)?;
    if obj.spread.iter().any(|&s| s < 0.0) {
        return Err(ctx.err(field("spread"), "must be ≥ 0 along every axis"));
    }
    ctx.non_negative(&field("tilt_deg"), obj.tilt_deg)?;
    if obj.count == 0 {
        return Err(ctx.err(field("count"), "must be ≥ 1"));
    }
    let spec = match obj.leaf.as_str() {
        "a" | "b" => LeafSpec::load(&obj.leaf),
        p => LeafSpec::read(&ctx.base.join(p)),
    }
    .map(|s| ctx.under_law(s))
    .map_err(|e| {
        ctx.err(
            field("leaf"),
            format!("cannot use leaf '{}': {e}", obj.leaf),
        )
    })?;
    if !spec.wind.is_still() {
        return Err(ctx.err(
            field("leaf"),
            format!(
                "leaf '{}' carries its own wind; in a scene the wind is the scene's [[wind]]",
                obj.leaf
            ),
        ));
    }
    let leaf = spec
        .model()
        .map_err(|e| ctx.err(field("leaf"), format!("invalid leaf '{}': {e}", obj.leaf)))?;
    Ok((spec, leaf))
}

/// A scene has one aerodynamic law for all its leaves: the first leaf's,
/// which every other must share.
fn one_law(
    ctx: &Ctx<'_>,
    b: &mut Builder,
    path: &str,
    obj: &LeafObject,
    leaf: &Model,
) -> Result<(), SceneError> {
    let field = |f: &str| format!("{path}.{f}");
    match &b.aero_from {
        None => {
            b.aero_from = Some(path.to_string());
            b.parts.aero = leaf.aero;
        }
        Some(first) if b.parts.aero != leaf.aero => {
            return Err(ctx.err(
                field("leaf"),
                format!(
                    "leaf '{}' uses the {} aerodynamic law but {first} uses the {}; a scene has one law for all its leaves",
                    obj.leaf,
                    leaf.aero.name(),
                    b.parts.aero.name()
                ),
            ));
        }
        Some(_) => {}
    }
    Ok(())
}

/// Where and how a copy is released: its offset within the group's
/// spread, and its attitude (a random tilt about a random horizontal
/// axis, a random yaw if asked, then the group's rotation `base`). The
/// draws' order is part of a scene's seed.
fn release(
    obj: &LeafObject,
    rng: &mut SplitMix,
    base: UnitQuaternion<f64>,
) -> (V3, UnitQuaternion<f64>) {
    let offset = V3::new(
        obj.spread[0] * rng.signed(),
        obj.spread[1] * rng.signed(),
        obj.spread[2] * rng.signed(),
    );
    let tilt_axis = rng.unit() * std::f64::consts::TAU;
    let tilt = obj.tilt_deg.to_radians() * rng.unit();
    let yaw = if obj.random_yaw {
        rng.unit() * std::f64::consts::TAU
    } else {
        0.0
    };
    let axis = Unit::new_normalize(V3::new(tilt_axis.cos(), tilt_axis.sin(), 0.0));
    let rotation = UnitQuaternion::from_axis_angle(&V3::z_axis(), yaw)
        * UnitQuaternion::from_axis_angle(&axis, tilt)
        * base;
    (offset, rotation)
}

/// A copy's triangles, and unless it is rigid its springs and hinges, its
/// particles numbered from `start`; a rigid leaf's internal forces are
/// pruned, said once (for the first copy).
fn add_elements(
    b: &mut Builder,
    path: &str,
    obj: &LeafObject,
    leaf: &Model,
    start: usize,
    rigid: bool,
    first: bool,
) {
    // Triangles keep their own coefficients; springs and hinges keep
    // their rest lengths and angles (both unchanged by a rigid motion).
    for t in &leaf.triangles {
        b.parts.triangles.push(Triangle {
            corners: t.corners.map(|c| start + c),
            ..*t
        });
        b.triangle_owner.push(path.to_string());
    }
    if rigid {
        if first && (!leaf.springs.is_empty() || !leaf.hinges.is_empty()) {
            b.pruned.push(format!(
            "{path} ({}): {} springs and {} hinges per copy inside a rigid body (internal forces cancel)",
            obj.name,
            leaf.springs.len(),
            leaf.hinges.len()
        ));
        }
    } else {
        for s in &leaf.springs {
            b.parts.springs.push(Spring {
                i: start + s.i,
                j: start + s.j,
                ..*s
            });
            b.spring_owner.push(path.to_string());
        }
        for h in &leaf.hinges {
            let mut h = *h;
            h.edge = h.edge.map(|c| start + c);
            h.apexes = h.apexes.map(|c| start + c);
            b.parts.hinges.push(h);
            b.hinge_owner.push(path.to_string());
        }
    }
}

pub(super) fn add_rigid(
    ctx: &Ctx<'_>,
    b: &mut Builder,
    names: &mut HashMap<String, String>,
    k: usize,
    obj: &RigidObject,
) -> Result<(), SceneError> {
    let path = format!("rigid[{k}]");
    let field = |f: &str| format!("{path}.{f}");
    check_name(ctx, &field("name"), &obj.name, names)?;
    ctx.positive(&field("mass"), obj.mass)?;
    ctx.non_negative(&field("alpha_n"), obj.alpha_n)?;
    ctx.non_negative(&field("alpha_t"), obj.alpha_t)?;
    ctx.vector(&field("position"), &obj.position)?;
    ctx.vector(&field("rotation_deg"), &obj.rotation_deg)?;
    ctx.vector(&field("velocity"), &obj.velocity)?;
    ctx.vector(&field("angular_velocity"), &obj.angular_velocity)?;
    let present = [
        ("size", obj.size.is_some()),
        ("radius", obj.radius.is_some()),
        ("height", obj.height.is_some()),
        ("segments", obj.segments.is_some()),
        ("rings", obj.rings.is_some()),
        ("base_mass", obj.base_mass.is_some()),
    ];
    let allowed: &[&str] = match obj.shape {
        Shape::Box => &["size"],
        Shape::Cylinder => &["radius", "height", "segments", "rings", "base_mass"],
    };
    if let Some((key, _)) = present
        .iter()
        .find(|(key, here)| *here && !allowed.contains(key))
    {
        return Err(ctx.err(
            field(key),
            format!("does not apply to shape \"{}\"", shape_name(obj.shape)),
        ));
    }
    let required = |key: &str, v: Option<f64>| {
        v.ok_or_else(|| {
            ctx.err(
                field(key),
                format!("shape \"{}\" requires `{key}`", shape_name(obj.shape)),
            )
        })
    };
    let part = match obj.shape {
        Shape::Box => {
            let size = obj
                .size
                .ok_or_else(|| ctx.err(field("size"), "shape \"box\" requires `size`"))?;
            for (axis, &s) in size.iter().enumerate() {
                ctx.positive(&format!("{}[{axis}]", field("size")), s)?;
            }
            shapes::cuboid(V3::from(size), obj.mass)
        }
        Shape::Cylinder => {
            let radius = required("radius", obj.radius)?;
            let height = required("height", obj.height)?;
            ctx.positive(&field("radius"), radius)?;
            ctx.positive(&field("height"), height)?;
            let segments = obj.segments.unwrap_or(16);
            let rings = obj.rings.unwrap_or(2);
            if segments < 3 {
                return Err(ctx.err(field("segments"), format!("must be ≥ 3, got {segments}")));
            }
            if rings < 2 {
                return Err(ctx.err(field("rings"), format!("must be ≥ 2, got {rings}")));
            }
            b.reserve(
                ctx,
                &field("segments"),
                &format!("a cylinder of {segments} segments × {rings} rings"),
                segments as f64 * rings as f64 + 1.0,
                0.0,
            )?;
            let wall_each = obj.mass / (segments as f64 * rings as f64);
            let base = match obj.base_mass {
                Some(m) => {
                    ctx.positive(&field("base_mass"), m)?;
                    m
                }
                None => wall_each,
            };
            shapes::bin(radius, height, segments, rings, obj.mass, base)
        }
    };
    if obj.alpha_n == 0.0 && obj.alpha_t == 0.0 {
        b.pruned.push(format!(
            "{path} ({}): {} surface triangles with αⁿ = αᵗ = 0",
            obj.name,
            part.triangles.len()
        ));
    }
    let rotation = rotation_xyz(obj.rotation_deg);
    let ids = b.add_part(
        &path,
        &part,
        &[],
        (obj.alpha_n, obj.alpha_t),
        V3::zeros(),
        rotation,
        V3::from(obj.position),
        V3::from(obj.velocity),
        V3::from(obj.angular_velocity),
    );
    let local = Model::new(ModelParts {
        mass: part.mass.clone(),
        fixed: part.fixed.clone(),
        rest_position: part.position.clone(),
        ..Default::default()
    })
    .map_err(|e| ctx.err(path.clone(), e.to_string()))?;
    let pose = PoseFrame {
        model: local,
        initial: rotation,
    };
    b.push_object(
        obj.name.clone(),
        ObjectKind::Rigid,
        ids,
        Some(pose),
        true,
        &path,
    );
    b.set_surface(part.triangles.clone());
    Ok(())
}

fn shape_name(s: Shape) -> &'static str {
    match s {
        Shape::Box => "box",
        Shape::Cylinder => "cylinder",
    }
}

pub(super) fn add_sheet(
    ctx: &Ctx<'_>,
    b: &mut Builder,
    names: &mut HashMap<String, String>,
    k: usize,
    obj: &SheetObject,
) -> Result<(), SceneError> {
    let path = format!("sheet[{k}]");
    let field = |f: &str| format!("{path}.{f}");
    check_name(ctx, &field("name"), &obj.name, names)?;
    for (axis, &s) in obj.size.iter().enumerate() {
        ctx.positive(&format!("{}[{axis}]", field("size")), s)?;
    }
    for (axis, &c) in obj.cells.iter().enumerate() {
        if c == 0 {
            return Err(ctx.err(format!("{}[{axis}]", field("cells")), "must be ≥ 1"));
        }
    }
    ctx.positive(&field("mass"), obj.mass)?;
    ctx.positive(&field("stiffness"), obj.stiffness)?;
    let shear = obj.shear_stiffness.unwrap_or(obj.stiffness);
    ctx.non_negative(&field("shear_stiffness"), shear)?;
    ctx.non_negative(&field("damping"), obj.damping)?;
    if let Some(e) = obj.break_strain {
        ctx.positive(&field("break_strain"), e)?;
    }
    ctx.non_negative(&field("alpha_n"), obj.alpha_n)?;
    ctx.non_negative(&field("alpha_t"), obj.alpha_t)?;
    ctx.vector(&field("position"), &obj.position)?;
    ctx.vector(&field("rotation_deg"), &obj.rotation_deg)?;
    ctx.vector(&field("velocity"), &obj.velocity)?;
    let [nx, ny] = obj.cells;
    let (fx, fy) = (nx as f64, ny as f64);
    b.reserve(
        ctx,
        &field("cells"),
        &format!("a sheet of {nx} × {ny} cells"),
        (fx + 1.0) * (fy + 1.0),
        fx * (fy + 1.0) + fy * (fx + 1.0) + 2.0 * fx * fy,
    )?;
    let mut part = shapes::sheet(
        obj.size[0],
        obj.size[1],
        nx,
        ny,
        obj.mass,
        obj.stiffness,
        shear,
        obj.damping,
        obj.break_strain,
    );
    let top = ny * (nx + 1);
    match obj.pin {
        Pin::None => {}
        Pin::TopEdge => part.fixed[top..].iter_mut().for_each(|f| *f = true),
        Pin::TopCorners => {
            part.fixed[top] = true;
            part.fixed[top + nx] = true;
        }
        Pin::Corners => {
            for i in [0, nx, top, top + nx] {
                part.fixed[i] = true;
            }
        }
        Pin::Border => {
            for j in 0..=ny {
                for i in 0..=nx {
                    if i == 0 || j == 0 || i == nx || j == ny {
                        part.fixed[j * (nx + 1) + i] = true;
                    }
                }
            }
        }
    }
    let ids = b.add_part(
        &path,
        &part,
        &[],
        (obj.alpha_n, obj.alpha_t),
        V3::zeros(),
        rotation_xyz(obj.rotation_deg),
        V3::from(obj.position),
        V3::from(obj.velocity),
        V3::zeros(),
    );
    b.push_object(obj.name.clone(), ObjectKind::Sheet, ids, None, false, &path);
    b.set_surface(part.triangles.clone());
    Ok(())
}

/// Resolves a rope end: a fixed point's (or one-particle object's) name, or
/// `OBJECT:K` for particle K of an object.
fn rope_end(ctx: &Ctx<'_>, b: &Builder, field: &str, end: &str) -> Result<usize, SceneError> {
    let (name, index) = match end.rsplit_once(':') {
        Some((name, k)) => {
            let k: usize = k.trim().parse().map_err(|_| {
                ctx.err(
                    field,
                    format!("'{end}': the particle after ':' must be a whole number"),
                )
            })?;
            (name, Some(k))
        }
        None => (end, None),
    };
    let Some(obj) = b.objects.iter().find(|o| o.name == name) else {
        return Err(ctx.err(
            field,
            format!(
                "no object named '{name}' (ropes come last; name a [[fixed]] point or OBJECT:K)"
            ),
        ));
    };
    match (index, obj.particles.len()) {
        (Some(k), n) if k < n => Ok(obj.particles[k]),
        (Some(k), n) => Err(ctx.err(
            field,
            format!("object '{name}' has {n} particles; {k} is out of range"),
        )),
        (None, 1) => Ok(obj.particles[0]),
        (None, n) => Err(ctx.err(
            field,
            format!("object '{name}' has {n} particles; say which with '{name}:K'"),
        )),
    }
}

pub(super) fn add_rope(
    ctx: &Ctx<'_>,
    b: &mut Builder,
    names: &mut HashMap<String, String>,
    k: usize,
    obj: &RopeObject,
) -> Result<(), SceneError> {
    let path = format!("rope[{k}]");
    let field = |f: &str| format!("{path}.{f}");
    check_name(ctx, &field("name"), &obj.name, names)?;
    if obj.segments < 2 {
        return Err(ctx.err(
            field("segments"),
            format!("must be ≥ 2, got {}", obj.segments),
        ));
    }
    ctx.positive(&field("mass"), obj.mass)?;
    ctx.positive(&field("stiffness"), obj.stiffness)?;
    ctx.non_negative(&field("damping"), obj.damping)?;
    ctx.non_negative(&field("drag"), obj.drag)?;
    ctx.finite(&field("slack"), obj.slack)?;
    if obj.slack <= -1.0 {
        return Err(ctx.err(field("slack"), format!("must be > −1, got {}", obj.slack)));
    }
    if let Some(e) = obj.break_strain {
        ctx.positive(&field("break_strain"), e)?;
    }
    b.reserve(
        ctx,
        &field("segments"),
        &format!("a rope of {} segments", obj.segments),
        obj.segments as f64 - 1.0,
        obj.segments as f64,
    )?;
    let a = rope_end(ctx, b, &field("from"), &obj.from)?;
    let z = rope_end(ctx, b, &field("to"), &obj.to)?;
    if a == z {
        return Err(ctx.err(field("to"), "both ends are the same particle"));
    }
    let (xa, xz) = (b.parts.rest_position[a], b.parts.rest_position[z]);
    let (va, vz) = (b.velocity[a], b.velocity[z]);
    let span = (xz - xa).norm();
    if span == 0.0 {
        return Err(ctx.err(field("to"), "the two ends coincide"));
    }
    let n = obj.segments;
    let each = obj.mass / (n - 1) as f64;
    let mut chain = vec![a];
    for s in 1..n {
        let f = s as f64 / n as f64;
        let i = b.parts.mass.len();
        b.parts.mass.push(each);
        b.parts.fixed.push(false);
        b.parts.particle_drag.push(obj.drag);
        b.parts.rest_position.push(xa + (xz - xa) * f);
        b.velocity.push(va + (vz - va) * f);
        b.particle_owner.push(path.clone());
        chain.push(i);
    }
    chain.push(z);
    let rest = (1.0 + obj.slack) * span / n as f64;
    for w in chain.windows(2) {
        b.parts.springs.push(Spring {
            i: w[0],
            j: w[1],
            rest_length: rest,
            stiffness: obj.stiffness,
            damping: obj.damping,
            break_strain: obj.break_strain,
        });
        b.spring_owner.push(path.clone());
    }
    b.push_object(
        obj.name.clone(),
        ObjectKind::Rope,
        chain,
        None,
        false,
        &path,
    );
    Ok(())
}
