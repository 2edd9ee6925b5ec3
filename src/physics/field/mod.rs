//! Wind velocity fields: superposed potential-flow primitives (the paper's
//! section 2.2, eq. 4–5 and figure 2).
//!
//! A [`WindField`] maps a position and a time to the wind velocity G(x, t)
//! (m/s). Each [`Primitive`] is an analytic solution of Laplace's equation
//! ∇²φ = 0 with v = ∇φ, so any sum of them is still inviscid, incompressible
//! and irrotational, except where we deliberately depart from the paper:
//!
//! - **Regularised cores.** Sources, sinks and vortices are singular on their
//!   point or axis; each carries a `core_radius` that smooths the core so G is
//!   finite everywhere (a vortex core has vorticity, a smoothed source has a
//!   distributed divergence that integrates to the same total flux).
//! - **Bounds and moving fronts** multiply a primitive by a smooth weight in
//!   [0, 1]; inside the falloff band the field is no longer divergence-free.
//!   They realise the paper's "bounded" fields and the shockwave of its
//!   section 4.2 directly instead of with rows of sinks.
//! - **Keyframed strength** makes any primitive time-varying.
//!
//! The paper's "source" formula v_r = a/(2πr), φ = a ln(r)/2π, is the 2-D
//! *line* source (r is the distance to an axis); here it is
//! [`Flow::LineSource`]. A true 3-D point source is [`Flow::PointSource`].
//!
//! Units: SI, f64, z up. Velocities m/s, lengths m, time s.
//!
//! The evaluation path ([`WindField::velocity`]) does not allocate: unit axes,
//! normals and constant factors are computed once when a primitive is built
//! or deserialised. Call [`WindField::validate`] after loading; fields that
//! fail validation may evaluate to NaN.

use std::f64::consts::PI;
use std::fmt;

use nalgebra::Vector3;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// Peak of the Lamb–Oseen profile (1 − e^{−s²})/s, reached at s = ρ/r_c ≈ 1.12091,
/// rounded up so [`WindField::speed_bound`] stays an upper bound.
const LAMB_OSEEN_PEAK: f64 = 0.638_172_7;

/// Peak of the smoothed point-source profile s/(1 + s²)^{3/2} = 2/(3√3), at s = 1/√2.
const POINT_SOURCE_PEAK: f64 = 0.384_900_179_459_750_5;

/// A validation failure: which item of the field is wrong, and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{item}: {reason}")]
pub struct FieldError {
    /// Path of the offending item, e.g. `wind[2].core_radius`.
    pub item: String,
    /// What is wrong with it.
    pub reason: String,
}

impl FieldError {
    fn new(item: impl Into<String>, reason: impl Into<String>) -> Self {
        Self {
            item: item.into(),
            reason: reason.into(),
        }
    }

    /// Prefixes the item path, so nested checks can name items relative to their parent.
    fn within(mut self, parent: &str) -> Self {
        self.item = format!("{parent}.{}", self.item);
        self
    }
}

/// Superposition of wind primitives (the paper's eq. 4–5 and figure 2):
/// G(x, t) = Σ_i G_i(x, t).
///
/// In TOML it is an array of tables `[[wind]]`, one per [`Primitive`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct WindField {
    primitives: Vec<Primitive>,
}

impl WindField {
    /// Still air: no primitives, G ≡ 0.
    pub fn still() -> Self {
        Self::default()
    }

    /// A field made of the given primitives, summed.
    pub fn new(primitives: Vec<Primitive>) -> Self {
        Self { primitives }
    }

    /// The primitives, in the order they are summed.
    pub fn primitives(&self) -> &[Primitive] {
        &self.primitives
    }

    /// True when there are no primitives, so callers may skip wind evaluation.
    pub fn is_still(&self) -> bool {
        self.primitives.is_empty()
    }

    /// Wind velocity G(x, t) in m/s at position `x` (m) and time `t` (s).
    #[inline]
    pub fn velocity(&self, x: &Vector3<f64>, t: f64) -> Vector3<f64> {
        let mut g = Vector3::zeros();
        for p in &self.primitives {
            g += p.velocity(x, t);
        }
        g
    }

    /// Checks every number of every primitive.
    ///
    /// # Errors
    /// The first bad item, named as `wind[i].name` (e.g. `wind[2].core_radius`,
    /// `wind[0].bounds.falloff`, `wind[1].keys[3]`).
    pub fn validate(&self) -> Result<(), FieldError> {
        for (i, p) in self.primitives.iter().enumerate() {
            p.validate().map_err(|e| e.within(&format!("wind[{i}]")))?;
        }
        Ok(())
    }

    /// Upper bound of |G| over all space and time (m/s): the sum of each
    /// primitive's peak speed times its largest |keyframe multiplier|. Exact
    /// for a single primitive without bounds; finite because cores are
    /// regularised.
    pub fn speed_bound(&self) -> f64 {
        self.primitives.iter().map(Primitive::speed_bound).sum()
    }
}

/// Core model of a line vortex, which removes the 1/ρ singularity on its axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VortexCore {
    /// Lamb–Oseen (viscous) core: v_θ = Γ/(2πρ)·(1 − e^{−ρ²/r_c²}); smooth
    /// everywhere, peak 0.6382·Γ/(2π r_c) at ρ = 1.1209 r_c. The default.
    #[default]
    LambOseen,
    /// Rankine core: solid-body rotation v_θ = Γρ/(2πR²) for ρ < R, free vortex
    /// Γ/(2πρ) outside; continuous, with a kink at ρ = R.
    Rankine,
}

/// The potential flow a primitive describes (the paper's figure 2).
///
/// Notation: d = x − point; for line primitives with unit axis ê,
/// d⊥ = d − (d·ê)ê and ρ = |d⊥| (distance to the axis).
#[derive(Clone, Debug, PartialEq)]
pub enum Flow {
    /// Uniform flow, φ = ax + by + cz, v = (a, b, c). TOML kind `uniform`.
    Uniform {
        /// Wind velocity, m/s.
        velocity: Vector3<f64>,
    },
    /// 3-D point source, φ = −a/(4πr), v = a r̂/(4πr²); `flux` a is the volume
    /// outflow in m³/s (negative a is a sink). Core smoothing (Plummer):
    /// v = a d/(4π(r² + ε²)^{3/2}), ε = `core_radius`, the gradient of
    /// φ = −a/(4π√(r²+ε²)); flux through a centred sphere of radius R is
    /// a R³/(R² + ε²)^{3/2}. TOML kind `point_source`.
    PointSource {
        /// Location of the source, m.
        point: Vector3<f64>,
        /// Volume outflow a, m³/s.
        flux: f64,
        /// Smoothing length ε > 0, m.
        core_radius: f64,
    },
    /// 3-D point sink: a [`Flow::PointSource`] of flux −a, so a positive `flux`
    /// (m³/s) means inflow. TOML kind `point_sink`.
    PointSink {
        /// Location of the sink, m.
        point: Vector3<f64>,
        /// Volume inflow a, m³/s.
        flux: f64,
        /// Smoothing length ε > 0, m.
        core_radius: f64,
    },
    /// 2-D line source along an axis (the paper's "source": φ = a ln(ρ)/2π,
    /// v_ρ = a/(2πρ), with ρ the distance to the axis); `flux` a is the outflow
    /// per unit length of axis, m²/s. Core smoothing:
    /// v = a d⊥/(2π(ρ² + ε²)), ε = `core_radius`; flux per unit length through
    /// a coaxial cylinder of radius R is a R²/(R² + ε²). TOML kind `line_source`.
    LineSource {
        /// A point on the axis, m.
        point: Vector3<f64>,
        /// Axis direction (any length; normalised when built).
        axis: Vector3<f64>,
        /// Outflow per unit length a, m²/s.
        flux: f64,
        /// Smoothing length ε > 0, m.
        core_radius: f64,
    },
    /// 2-D line sink (the paper's "sink"): a [`Flow::LineSource`] of flux −a,
    /// so a positive `flux` (m²/s) means inflow. TOML kind `line_sink`.
    LineSink {
        /// A point on the axis, m.
        point: Vector3<f64>,
        /// Axis direction (any length; normalised when built).
        axis: Vector3<f64>,
        /// Inflow per unit length a, m²/s.
        flux: f64,
        /// Smoothing length ε > 0, m.
        core_radius: f64,
    },
    /// Line vortex (the paper's "vortex"): φ = Γθ/(2π), v_θ = Γ/(2πρ),
    /// rotating by the right-hand rule about the axis (v = Γ ê × d⊥/(2πρ²)).
    /// `circulation` Γ in m²/s; the core is regularised per [`VortexCore`].
    /// TOML kind `line_vortex`.
    LineVortex {
        /// A point on the axis, m.
        point: Vector3<f64>,
        /// Axis direction (any length; normalised when built).
        axis: Vector3<f64>,
        /// Circulation Γ, m²/s.
        circulation: f64,
        /// Core radius r_c (Lamb–Oseen) or R (Rankine) > 0, m.
        core_radius: f64,
        /// Core model.
        core: VortexCore,
    },
}

/// Region in which a bounded primitive acts at full strength.
#[derive(Clone, Debug, PartialEq)]
pub enum Region {
    /// Ball of `radius` m around `center`. TOML `shape = "sphere"`.
    Sphere {
        /// Centre, m.
        center: Vector3<f64>,
        /// Radius ≥ 0, m.
        radius: f64,
    },
    /// Axis-aligned box. TOML `shape = "box"`.
    Box {
        /// Lower corner, m.
        min: Vector3<f64>,
        /// Upper corner, m (each component ≥ `min`'s).
        max: Vector3<f64>,
    },
    /// Infinite tube of `radius` m around an axis. TOML `shape = "cylinder"`.
    Cylinder {
        /// A point on the axis, m.
        point: Vector3<f64>,
        /// Axis direction (any length; normalised when built).
        axis: Vector3<f64>,
        /// Radius ≥ 0, m.
        radius: f64,
    },
}

/// Limits a primitive to a region (the paper's "bounded" fields; Blender/Maya
/// "max distance" with a falloff).
///
/// With d the distance from x to the region (0 inside) and s = d/`falloff`,
/// the primitive is multiplied by w = 1 − (6s⁵ − 15s⁴ + 10s³) for 0 < s < 1
/// (a quintic smoothstep: w and its first two derivatives are continuous),
/// w = 1 inside, w = 0 beyond; so the "max distance" is the region's size plus
/// `falloff`. `falloff = 0` gives a hard (discontinuous) edge.
#[derive(Clone, Debug, PartialEq)]
pub struct Bounds {
    /// Full-strength region.
    pub region: Region,
    /// Width of the smooth falloff band outside the region, m (≥ 0).
    pub falloff: f64,
}

/// A moving half-space boundary (the paper's section 4.2 shockwave: the
/// boundaries of uniform fields moved up through the leaves).
///
/// The front is the plane n̂·x = offset + speed·t. The primitive acts fully
/// behind it (n̂·x ≤ offset(t)) and fades to zero over `falloff` m ahead of
/// it with the same quintic smoothstep as [`Bounds`]. A positive speed sweeps
/// the active side forward along n̂.
#[derive(Clone, Debug, PartialEq)]
pub struct Front {
    /// Direction the front faces and moves along (any length; normalised when built).
    pub normal: Vector3<f64>,
    /// Plane offset along the unit normal at t = 0, m.
    pub offset: f64,
    /// Speed of the plane along the unit normal, m/s (TOML default 0).
    pub speed: f64,
    /// Width of the smooth falloff band ahead of the plane, m (≥ 0).
    pub falloff: f64,
}

impl Front {
    /// Plane offset at time `t`: offset + speed·t, m.
    pub fn offset_at(&self, t: f64) -> f64 {
        self.offset + self.speed * t
    }
}

/// How [`Keyframes`] are interpolated between keys.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Interpolation {
    /// Straight line between neighbouring keys (the default).
    #[default]
    Linear,
    /// Hold each key's value until the next key.
    Step,
}

/// Time-varying strength multiplier: keys (time s, multiplier), times
/// strictly increasing. Before the first key the first value holds, after the
/// last key the last value holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Keyframes {
    /// (time, multiplier) pairs, strictly increasing in time.
    pub keys: Vec<(f64, f64)>,
    /// Interpolation between keys.
    pub interpolation: Interpolation,
}

impl Keyframes {
    /// Multiplier at time `t`. An empty key list (rejected by validation) gives 1.
    #[inline]
    pub fn value(&self, t: f64) -> f64 {
        let keys = &self.keys;
        let (Some(&(t_first, v_first)), Some(&(t_last, v_last))) = (keys.first(), keys.last())
        else {
            return 1.0;
        };
        // NaN (a clock gone wrong) takes the first key rather than an index
        // off the end.
        if t.is_nan() || t <= t_first {
            return v_first;
        }
        if t >= t_last {
            return v_last;
        }
        // First key strictly after t; 1 ≤ i < len because t_first < t < t_last.
        let i = keys.partition_point(|&(tk, _)| tk <= t);
        let (t0, v0) = keys[i - 1];
        let (t1, v1) = keys[i];
        match self.interpolation {
            Interpolation::Step => v0,
            Interpolation::Linear => v0 + (v1 - v0) * ((t - t0) / (t1 - t0)),
        }
    }

    /// Largest |multiplier| over all time (both interpolations stay within the keys).
    pub fn max_abs(&self) -> f64 {
        self.keys.iter().fold(0.0, |m, &(_, v)| m.max(v.abs()))
    }
}

/// One wind primitive: a [`Flow`], optionally limited by [`Bounds`] and a
/// moving [`Front`], and scaled by keyframed strength:
/// G_i(x, t) = k(t) · w_bounds(x) · w_front(x, t) · v_flow(x).
#[derive(Clone, Debug, PartialEq)]
pub struct Primitive {
    flow: Flow,
    bounds: Option<Bounds>,
    front: Option<Front>,
    keys: Option<Keyframes>,
    compiled: Compiled,
}

impl Primitive {
    /// An unbounded, constant-strength primitive.
    pub fn new(flow: Flow) -> Self {
        let compiled = Compiled::flow_only(&flow);
        Self {
            flow,
            bounds: None,
            front: None,
            keys: None,
            compiled,
        }
    }

    /// Uniform wind of `velocity` m/s.
    pub fn uniform(velocity: Vector3<f64>) -> Self {
        Self::new(Flow::Uniform { velocity })
    }

    /// Limits the primitive to a region.
    #[must_use]
    pub fn with_bounds(mut self, bounds: Bounds) -> Self {
        self.compiled.region = Some(RegionEval::new(&bounds));
        self.bounds = Some(bounds);
        self
    }

    /// Makes the primitive act only behind a moving front.
    #[must_use]
    pub fn with_front(mut self, front: Front) -> Self {
        self.compiled.front = Some(FrontEval::new(&front));
        self.front = Some(front);
        self
    }

    /// Scales the primitive by a keyframed multiplier.
    #[must_use]
    pub fn with_keys(mut self, keys: Keyframes) -> Self {
        self.keys = Some(keys);
        self
    }

    /// The flow this primitive describes.
    pub fn flow(&self) -> &Flow {
        &self.flow
    }

    /// The region limit, if any.
    pub fn bounds(&self) -> Option<&Bounds> {
        self.bounds.as_ref()
    }

    /// The moving front, if any.
    pub fn front(&self) -> Option<&Front> {
        self.front.as_ref()
    }

    /// The strength keyframes, if any.
    pub fn keys(&self) -> Option<&Keyframes> {
        self.keys.as_ref()
    }

    /// This primitive's contribution G_i(x, t), m/s.
    #[inline]
    pub fn velocity(&self, x: &Vector3<f64>, t: f64) -> Vector3<f64> {
        let mut gain = match &self.keys {
            Some(k) => k.value(t),
            None => 1.0,
        };
        if let Some(r) = &self.compiled.region {
            gain *= r.weight(x);
        }
        if let Some(f) = &self.compiled.front {
            gain *= f.weight(x, t);
        }
        // Skip the flow entirely outside its region or before its keys start.
        if gain == 0.0 {
            return Vector3::zeros();
        }
        self.compiled.flow.velocity(x) * gain
    }

    /// Peak |G_i| over space and time, m/s (weights are ≤ 1, so ignored).
    pub fn speed_bound(&self) -> f64 {
        let peak = match &self.flow {
            Flow::Uniform { velocity } => velocity.norm(),
            Flow::PointSource {
                flux, core_radius, ..
            }
            | Flow::PointSink {
                flux, core_radius, ..
            } => POINT_SOURCE_PEAK * flux.abs() / (4.0 * PI * core_radius * core_radius),
            Flow::LineSource {
                flux, core_radius, ..
            }
            | Flow::LineSink {
                flux, core_radius, ..
            } => flux.abs() / (4.0 * PI * core_radius),
            Flow::LineVortex {
                circulation,
                core_radius,
                core,
                ..
            } => {
                let free = circulation.abs() / (2.0 * PI * core_radius);
                match core {
                    VortexCore::LambOseen => LAMB_OSEEN_PEAK * free,
                    VortexCore::Rankine => free,
                }
            }
        };
        let gain = self.keys.as_ref().map_or(1.0, Keyframes::max_abs);
        peak * gain
    }

    /// Checks this primitive; items are named relative to it (`core_radius`).
    fn validate(&self) -> Result<(), FieldError> {
        match &self.flow {
            Flow::Uniform { velocity } => finite_vector(velocity, "velocity")?,
            Flow::PointSource {
                point,
                flux,
                core_radius,
            }
            | Flow::PointSink {
                point,
                flux,
                core_radius,
            } => {
                finite_vector(point, "point")?;
                finite(*flux, "flux")?;
                positive(*core_radius, "core_radius")?;
            }
            Flow::LineSource {
                point,
                axis,
                flux,
                core_radius,
            }
            | Flow::LineSink {
                point,
                axis,
                flux,
                core_radius,
            } => {
                finite_vector(point, "point")?;
                direction(axis, "axis")?;
                finite(*flux, "flux")?;
                positive(*core_radius, "core_radius")?;
            }
            Flow::LineVortex {
                point,
                axis,
                circulation,
                core_radius,
                ..
            } => {
                finite_vector(point, "point")?;
                direction(axis, "axis")?;
                finite(*circulation, "circulation")?;
                positive(*core_radius, "core_radius")?;
            }
        }
        if let Some(b) = &self.bounds {
            validate_bounds(b).map_err(|e| e.within("bounds"))?;
        }
        if let Some(f) = &self.front {
            validate_front(f).map_err(|e| e.within("front"))?;
        }
        if let Some(k) = &self.keys {
            validate_keys(k)?;
        }
        Ok(())
    }
}

fn validate_bounds(b: &Bounds) -> Result<(), FieldError> {
    match &b.region {
        Region::Sphere { center, radius } => {
            finite_vector(center, "center")?;
            non_negative(*radius, "radius")?;
        }
        Region::Box { min, max } => {
            finite_vector(min, "min")?;
            finite_vector(max, "max")?;
            for (i, c) in ["x", "y", "z"].iter().enumerate() {
                if min[i] > max[i] {
                    return Err(FieldError::new(
                        "min",
                        format!("min.{c} = {} exceeds max.{c} = {}", min[i], max[i]),
                    ));
                }
            }
        }
        Region::Cylinder {
            point,
            axis,
            radius,
        } => {
            finite_vector(point, "point")?;
            direction(axis, "axis")?;
            non_negative(*radius, "radius")?;
        }
    }
    non_negative(b.falloff, "falloff")
}

fn validate_front(f: &Front) -> Result<(), FieldError> {
    direction(&f.normal, "normal")?;
    finite(f.offset, "offset")?;
    finite(f.speed, "speed")?;
    non_negative(f.falloff, "falloff")
}

fn validate_keys(k: &Keyframes) -> Result<(), FieldError> {
    if k.keys.is_empty() {
        return Err(FieldError::new(
            "keys",
            "empty keyframe list (omit `keys` for constant strength)",
        ));
    }
    for (i, &(t, v)) in k.keys.iter().enumerate() {
        let item = format!("keys[{i}]");
        if !t.is_finite() || !v.is_finite() {
            return Err(FieldError::new(item, format!("non-finite key ({t}, {v})")));
        }
        if i > 0 {
            let prev = k.keys[i - 1].0;
            if t <= prev {
                return Err(FieldError::new(
                    item,
                    format!("time {t} is not after the previous key's time {prev}"),
                ));
            }
        }
    }
    Ok(())
}

fn finite(x: f64, item: &str) -> Result<(), FieldError> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(FieldError::new(item, format!("must be finite, got {x}")))
    }
}

fn positive(x: f64, item: &str) -> Result<(), FieldError> {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err(FieldError::new(
            item,
            format!("must be finite and > 0, got {x}"),
        ))
    }
}

fn non_negative(x: f64, item: &str) -> Result<(), FieldError> {
    if x.is_finite() && x >= 0.0 {
        Ok(())
    } else {
        Err(FieldError::new(
            item,
            format!("must be finite and >= 0, got {x}"),
        ))
    }
}

fn finite_vector(v: &Vector3<f64>, item: &str) -> Result<(), FieldError> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(FieldError::new(
            item,
            format!("must be finite, got [{}, {}, {}]", v.x, v.y, v.z),
        ))
    }
}

fn direction(v: &Vector3<f64>, item: &str) -> Result<(), FieldError> {
    finite_vector(v, item)?;
    let n = v.norm();
    // A norm that under- or overflows cannot be normalised reliably.
    if n > 0.0 && n.is_finite() && (v / n).iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(FieldError::new(
            item,
            "must be a non-zero direction".to_string(),
        ))
    }
}

// ---------------------------------------------------------------------------
// Precomputed evaluation data (unit axes, constant factors), built once.

#[derive(Clone, Debug, PartialEq)]
struct Compiled {
    flow: FlowEval,
    region: Option<RegionEval>,
    front: Option<FrontEval>,
}

impl Compiled {
    fn flow_only(flow: &Flow) -> Self {
        Self {
            flow: FlowEval::new(flow),
            region: None,
            front: None,
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
enum FlowEval {
    Uniform {
        velocity: Vector3<f64>,
    },
    /// v = coef·d/(r² + ε²)^{3/2}, coef = ±a/(4π).
    PointSource {
        point: Vector3<f64>,
        coef: f64,
        eps2: f64,
    },
    /// v = coef·d⊥/(ρ² + ε²), coef = ±a/(2π).
    LineSource {
        point: Vector3<f64>,
        axis: Vector3<f64>,
        coef: f64,
        eps2: f64,
    },
    /// v = coef·f(ρ²/r_c²)·(ê × d), coef = Γ/(2π r_c²), f(q) = (1 − e^{−q})/q.
    LambOseen {
        point: Vector3<f64>,
        axis: Vector3<f64>,
        coef: f64,
        inv_rc2: f64,
    },
    /// v = coef·(ê × d)/max(ρ², R²), coef = Γ/(2π).
    Rankine {
        point: Vector3<f64>,
        axis: Vector3<f64>,
        coef: f64,
        r2: f64,
    },
}

impl FlowEval {
    fn new(flow: &Flow) -> Self {
        match *flow {
            Flow::Uniform { velocity } => Self::Uniform { velocity },
            Flow::PointSource {
                point,
                flux,
                core_radius,
            } => Self::point_source(point, flux, core_radius),
            Flow::PointSink {
                point,
                flux,
                core_radius,
            } => Self::point_source(point, -flux, core_radius),
            Flow::LineSource {
                point,
                axis,
                flux,
                core_radius,
            } => Self::line_source(point, axis, flux, core_radius),
            Flow::LineSink {
                point,
                axis,
                flux,
                core_radius,
            } => Self::line_source(point, axis, -flux, core_radius),
            Flow::LineVortex {
                point,
                axis,
                circulation,
                core_radius,
                core,
            } => {
                let axis = axis.normalize();
                let r2 = core_radius * core_radius;
                match core {
                    VortexCore::LambOseen => Self::LambOseen {
                        point,
                        axis,
                        coef: circulation / (2.0 * PI * r2),
                        inv_rc2: 1.0 / r2,
                    },
                    VortexCore::Rankine => Self::Rankine {
                        point,
                        axis,
                        coef: circulation / (2.0 * PI),
                        r2,
                    },
                }
            }
        }
    }

    fn point_source(point: Vector3<f64>, flux: f64, core_radius: f64) -> Self {
        Self::PointSource {
            point,
            coef: flux / (4.0 * PI),
            eps2: core_radius * core_radius,
        }
    }

    fn line_source(point: Vector3<f64>, axis: Vector3<f64>, flux: f64, core_radius: f64) -> Self {
        Self::LineSource {
            point,
            axis: axis.normalize(),
            coef: flux / (2.0 * PI),
            eps2: core_radius * core_radius,
        }
    }

    #[inline]
    fn velocity(&self, x: &Vector3<f64>) -> Vector3<f64> {
        match self {
            Self::Uniform { velocity } => *velocity,
            Self::PointSource { point, coef, eps2 } => {
                let d = x - point;
                let s = d.norm_squared() + eps2;
                d * (coef / (s * s.sqrt()))
            }
            Self::LineSource {
                point,
                axis,
                coef,
                eps2,
            } => {
                let d = x - point;
                let perp = d - axis * axis.dot(&d);
                perp * (coef / (perp.norm_squared() + eps2))
            }
            Self::LambOseen {
                point,
                axis,
                coef,
                inv_rc2,
            } => {
                let d = x - point;
                // ê × d = ê × d⊥, so the axial part needs no removal.
                let tangent = axis.cross(&d);
                let q = tangent.norm_squared() * inv_rc2;
                tangent * (coef * one_minus_exp_over(q))
            }
            Self::Rankine {
                point,
                axis,
                coef,
                r2,
            } => {
                let d = x - point;
                let tangent = axis.cross(&d);
                // Inside the core the divisor is R² (solid-body rotation), so it is never 0.
                tangent * (coef / tangent.norm_squared().max(*r2))
            }
        }
    }
}

/// (1 − e^{−q})/q for q ≥ 0, with its limit 1 at q = 0 (the vortex axis).
#[inline]
fn one_minus_exp_over(q: f64) -> f64 {
    if q < 1e-6 {
        // Taylor series; truncation error q³/24 < 1e-19.
        1.0 - q * (0.5 - q / 6.0)
    } else {
        -(-q).exp_m1() / q
    }
}

/// Weight 1 for d ≤ 0, quintic smoothstep down to 0 at d = width, 0 beyond.
#[inline]
fn falloff_weight(d: f64, width: f64) -> f64 {
    if d <= 0.0 {
        1.0
    } else if d >= width {
        0.0
    } else {
        let s = d / width;
        1.0 - s * s * s * (10.0 + s * (6.0 * s - 15.0))
    }
}

#[derive(Clone, Debug, PartialEq)]
enum RegionShape {
    Sphere {
        center: Vector3<f64>,
        radius: f64,
    },
    Box {
        min: Vector3<f64>,
        max: Vector3<f64>,
    },
    Cylinder {
        point: Vector3<f64>,
        axis: Vector3<f64>,
        radius: f64,
    },
}

#[derive(Clone, Debug, PartialEq)]
struct RegionEval {
    shape: RegionShape,
    falloff: f64,
}

impl RegionEval {
    fn new(b: &Bounds) -> Self {
        let shape = match b.region {
            Region::Sphere { center, radius } => RegionShape::Sphere { center, radius },
            Region::Box { min, max } => RegionShape::Box { min, max },
            Region::Cylinder {
                point,
                axis,
                radius,
            } => RegionShape::Cylinder {
                point,
                axis: axis.normalize(),
                radius,
            },
        };
        Self {
            shape,
            falloff: b.falloff,
        }
    }

    /// Distance from x to the region, ≤ 0 inside.
    #[inline]
    fn distance(&self, x: &Vector3<f64>) -> f64 {
        match &self.shape {
            RegionShape::Sphere { center, radius } => (x - center).norm() - radius,
            RegionShape::Box { min, max } => {
                let outside = (min - x).sup(&(x - max)).sup(&Vector3::zeros());
                outside.norm()
            }
            RegionShape::Cylinder {
                point,
                axis,
                radius,
            } => axis.cross(&(x - point)).norm() - radius,
        }
    }

    #[inline]
    fn weight(&self, x: &Vector3<f64>) -> f64 {
        falloff_weight(self.distance(x), self.falloff)
    }
}

#[derive(Clone, Debug, PartialEq)]
struct FrontEval {
    normal: Vector3<f64>,
    offset: f64,
    speed: f64,
    falloff: f64,
}

impl FrontEval {
    fn new(f: &Front) -> Self {
        Self {
            normal: f.normal.normalize(),
            offset: f.offset,
            speed: f.speed,
            falloff: f.falloff,
        }
    }

    #[inline]
    fn weight(&self, x: &Vector3<f64>, t: f64) -> f64 {
        let ahead = self.normal.dot(x) - (self.offset + self.speed * t);
        falloff_weight(ahead, self.falloff)
    }
}

// ---------------------------------------------------------------------------
// Serde: a flat table per primitive (`kind` plus the keys that kind uses).
// A flat struct is used instead of a tagged enum because `deny_unknown_fields`
// does not combine with `#[serde(flatten)]` for the shared keys (bounds, front,
// keys), and keys that belong to another kind are rejected in the conversion.

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum Kind {
    Uniform,
    PointSource,
    PointSink,
    LineSource,
    LineSink,
    LineVortex,
}

impl fmt::Display for Kind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = match self {
            Kind::Uniform => "uniform",
            Kind::PointSource => "point_source",
            Kind::PointSink => "point_sink",
            Kind::LineSource => "line_source",
            Kind::LineSink => "line_sink",
            Kind::LineVortex => "line_vortex",
        };
        f.write_str(s)
    }
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PrimitiveSpec {
    kind: Kind,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    velocity: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    point: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    axis: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    flux: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    circulation: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    core_radius: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    core: Option<VortexCore>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    keys: Option<Vec<(f64, f64)>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    interpolation: Option<Interpolation>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    bounds: Option<BoundsSpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    front: Option<FrontSpec>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum Shape {
    Sphere,
    Box,
    Cylinder,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct BoundsSpec {
    shape: Shape,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    center: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    radius: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    min: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    max: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    point: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    axis: Option<[f64; 3]>,
    falloff: f64,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct FrontSpec {
    normal: [f64; 3],
    offset: f64,
    #[serde(default)]
    speed: f64,
    falloff: f64,
}

/// Takes a key the kind requires.
fn required<T>(value: Option<T>, key: &str, owner: &dyn fmt::Display) -> Result<T, String> {
    value.ok_or_else(|| format!("{owner} requires `{key}`"))
}

/// Rejects keys that are present but mean nothing for this kind.
fn reject_extra(
    present: &[(&str, bool)],
    allowed: &[&str],
    owner: &dyn fmt::Display,
) -> Result<(), String> {
    match present
        .iter()
        .find(|(key, here)| *here && !allowed.contains(key))
    {
        Some((key, _)) => Err(format!("`{key}` does not apply to {owner}")),
        None => Ok(()),
    }
}

impl PrimitiveSpec {
    fn into_primitive(self) -> Result<Primitive, String> {
        let kind = self.kind;
        let owner = format!("kind \"{kind}\"");
        let present = [
            ("velocity", self.velocity.is_some()),
            ("point", self.point.is_some()),
            ("axis", self.axis.is_some()),
            ("flux", self.flux.is_some()),
            ("circulation", self.circulation.is_some()),
            ("core_radius", self.core_radius.is_some()),
            ("core", self.core.is_some()),
        ];
        let allowed: &[&str] = match kind {
            Kind::Uniform => &["velocity"],
            Kind::PointSource | Kind::PointSink => &["point", "flux", "core_radius"],
            Kind::LineSource | Kind::LineSink => &["point", "axis", "flux", "core_radius"],
            Kind::LineVortex => &["point", "axis", "circulation", "core_radius", "core"],
        };
        reject_extra(&present, allowed, &owner)?;
        let v = |a: [f64; 3]| Vector3::from(a);
        let flow = match kind {
            Kind::Uniform => Flow::Uniform {
                velocity: v(required(self.velocity, "velocity", &owner)?),
            },
            Kind::PointSource | Kind::PointSink => {
                let point = v(required(self.point, "point", &owner)?);
                let flux = required(self.flux, "flux", &owner)?;
                let core_radius = required(self.core_radius, "core_radius", &owner)?;
                if kind == Kind::PointSource {
                    Flow::PointSource {
                        point,
                        flux,
                        core_radius,
                    }
                } else {
                    Flow::PointSink {
                        point,
                        flux,
                        core_radius,
                    }
                }
            }
            Kind::LineSource | Kind::LineSink => {
                let point = v(required(self.point, "point", &owner)?);
                let axis = v(required(self.axis, "axis", &owner)?);
                let flux = required(self.flux, "flux", &owner)?;
                let core_radius = required(self.core_radius, "core_radius", &owner)?;
                if kind == Kind::LineSource {
                    Flow::LineSource {
                        point,
                        axis,
                        flux,
                        core_radius,
                    }
                } else {
                    Flow::LineSink {
                        point,
                        axis,
                        flux,
                        core_radius,
                    }
                }
            }
            Kind::LineVortex => Flow::LineVortex {
                point: v(required(self.point, "point", &owner)?),
                axis: v(required(self.axis, "axis", &owner)?),
                circulation: required(self.circulation, "circulation", &owner)?,
                core_radius: required(self.core_radius, "core_radius", &owner)?,
                core: self.core.unwrap_or_default(),
            },
        };
        let mut p = Primitive::new(flow);
        match (self.keys, self.interpolation) {
            (Some(keys), interpolation) => {
                p = p.with_keys(Keyframes {
                    keys,
                    interpolation: interpolation.unwrap_or_default(),
                });
            }
            (None, Some(_)) => return Err("`interpolation` given without `keys`".to_string()),
            (None, None) => {}
        }
        if let Some(b) = self.bounds {
            p = p.with_bounds(b.into_bounds()?);
        }
        if let Some(f) = self.front {
            p = p.with_front(Front {
                normal: Vector3::from(f.normal),
                offset: f.offset,
                speed: f.speed,
                falloff: f.falloff,
            });
        }
        Ok(p)
    }

    fn from_primitive(p: &Primitive) -> Self {
        let a = |v: &Vector3<f64>| Some([v.x, v.y, v.z]);
        let mut s = PrimitiveSpec {
            kind: Kind::Uniform,
            velocity: None,
            point: None,
            axis: None,
            flux: None,
            circulation: None,
            core_radius: None,
            core: None,
            keys: p.keys.as_ref().map(|k| k.keys.clone()),
            interpolation: p.keys.as_ref().map(|k| k.interpolation),
            bounds: p.bounds.as_ref().map(BoundsSpec::from_bounds),
            front: p.front.as_ref().map(|f| FrontSpec {
                normal: [f.normal.x, f.normal.y, f.normal.z],
                offset: f.offset,
                speed: f.speed,
                falloff: f.falloff,
            }),
        };
        match &p.flow {
            Flow::Uniform { velocity } => s.velocity = a(velocity),
            Flow::PointSource {
                point,
                flux,
                core_radius,
            }
            | Flow::PointSink {
                point,
                flux,
                core_radius,
            } => {
                s.kind = if matches!(p.flow, Flow::PointSource { .. }) {
                    Kind::PointSource
                } else {
                    Kind::PointSink
                };
                s.point = a(point);
                s.flux = Some(*flux);
                s.core_radius = Some(*core_radius);
            }
            Flow::LineSource {
                point,
                axis,
                flux,
                core_radius,
            }
            | Flow::LineSink {
                point,
                axis,
                flux,
                core_radius,
            } => {
                s.kind = if matches!(p.flow, Flow::LineSource { .. }) {
                    Kind::LineSource
                } else {
                    Kind::LineSink
                };
                s.point = a(point);
                s.axis = a(axis);
                s.flux = Some(*flux);
                s.core_radius = Some(*core_radius);
            }
            Flow::LineVortex {
                point,
                axis,
                circulation,
                core_radius,
                core,
            } => {
                s.kind = Kind::LineVortex;
                s.point = a(point);
                s.axis = a(axis);
                s.circulation = Some(*circulation);
                s.core_radius = Some(*core_radius);
                s.core = Some(*core);
            }
        }
        s
    }
}

impl BoundsSpec {
    fn into_bounds(self) -> Result<Bounds, String> {
        let shape = self.shape;
        let owner = format!(
            "bounds shape \"{}\"",
            match shape {
                Shape::Sphere => "sphere",
                Shape::Box => "box",
                Shape::Cylinder => "cylinder",
            }
        );
        let present = [
            ("center", self.center.is_some()),
            ("radius", self.radius.is_some()),
            ("min", self.min.is_some()),
            ("max", self.max.is_some()),
            ("point", self.point.is_some()),
            ("axis", self.axis.is_some()),
        ];
        let allowed: &[&str] = match shape {
            Shape::Sphere => &["center", "radius"],
            Shape::Box => &["min", "max"],
            Shape::Cylinder => &["point", "axis", "radius"],
        };
        reject_extra(&present, allowed, &owner)?;
        let region = match shape {
            Shape::Sphere => Region::Sphere {
                center: Vector3::from(required(self.center, "center", &owner)?),
                radius: required(self.radius, "radius", &owner)?,
            },
            Shape::Box => Region::Box {
                min: Vector3::from(required(self.min, "min", &owner)?),
                max: Vector3::from(required(self.max, "max", &owner)?),
            },
            Shape::Cylinder => Region::Cylinder {
                point: Vector3::from(required(self.point, "point", &owner)?),
                axis: Vector3::from(required(self.axis, "axis", &owner)?),
                radius: required(self.radius, "radius", &owner)?,
            },
        };
        Ok(Bounds {
            region,
            falloff: self.falloff,
        })
    }

    fn from_bounds(b: &Bounds) -> Self {
        let a = |v: &Vector3<f64>| Some([v.x, v.y, v.z]);
        let mut s = BoundsSpec {
            shape: Shape::Sphere,
            center: None,
            radius: None,
            min: None,
            max: None,
            point: None,
            axis: None,
            falloff: b.falloff,
        };
        match &b.region {
            Region::Sphere { center, radius } => {
                s.center = a(center);
                s.radius = Some(*radius);
            }
            Region::Box { min, max } => {
                s.shape = Shape::Box;
                s.min = a(min);
                s.max = a(max);
            }
            Region::Cylinder {
                point,
                axis,
                radius,
            } => {
                s.shape = Shape::Cylinder;
                s.point = a(point);
                s.axis = a(axis);
                s.radius = Some(*radius);
            }
        }
        s
    }
}

impl Serialize for Primitive {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        PrimitiveSpec::from_primitive(self).serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for Primitive {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        PrimitiveSpec::deserialize(deserializer)?
            .into_primitive()
            .map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3;
    use proptest::prelude::*;

    type V3 = Vector3<f64>;

    fn v(x: f64, y: f64, z: f64) -> V3 {
        V3::new(x, y, z)
    }

    fn point_source(point: V3, flux: f64, core_radius: f64) -> Primitive {
        Primitive::new(Flow::PointSource {
            point,
            flux,
            core_radius,
        })
    }

    fn line_source(point: V3, axis: V3, flux: f64, core_radius: f64) -> Primitive {
        Primitive::new(Flow::LineSource {
            point,
            axis,
            flux,
            core_radius,
        })
    }

    fn vortex(
        point: V3,
        axis: V3,
        circulation: f64,
        core_radius: f64,
        core: VortexCore,
    ) -> Primitive {
        Primitive::new(Flow::LineVortex {
            point,
            axis,
            circulation,
            core_radius,
            core,
        })
    }

    /// J[(i, j)] = ∂v_i/∂x_j by central differences of step h.
    fn jacobian(f: &dyn Fn(&V3) -> V3, x: &V3, h: f64) -> Matrix3<f64> {
        let mut j = Matrix3::zeros();
        for k in 0..3 {
            let mut e = V3::zeros();
            e[k] = h;
            let col = (f(&(x + e)) - f(&(x - e))) / (2.0 * h);
            j.set_column(k, &col);
        }
        j
    }

    fn div_curl(f: &dyn Fn(&V3) -> V3, x: &V3, h: f64) -> (f64, V3) {
        let j = jacobian(f, x, h);
        let curl = v(
            j[(2, 1)] - j[(1, 2)],
            j[(0, 2)] - j[(2, 0)],
            j[(1, 0)] - j[(0, 1)],
        );
        (j.trace(), curl)
    }

    /// Two unit vectors completing a right-handed frame (e1, e2, axis).
    fn frame(axis: &V3) -> (V3, V3) {
        let a = axis.normalize();
        let helper = if a.x.abs() < 0.9 { V3::x() } else { V3::y() };
        let e1 = a.cross(&helper).normalize();
        let e2 = a.cross(&e1);
        (e1, e2)
    }

    /// ∮ G·dl on the circle centre + R(cos θ e1 + sin θ e2), trapezoid rule.
    fn circulation(f: &WindField, centre: &V3, axis: &V3, radius: f64, n: usize) -> f64 {
        let (e1, e2) = frame(axis);
        let dth = 2.0 * PI / n as f64;
        (0..n)
            .map(|k| {
                let th = k as f64 * dth;
                let x = centre + radius * (th.cos() * e1 + th.sin() * e2);
                let dl = radius * (-th.sin() * e1 + th.cos() * e2);
                f.velocity(&x, 0.0).dot(&dl) * dth
            })
            .sum()
    }

    /// Outward flux per unit length through that circle (a coaxial cylinder if centre is on the axis).
    fn ring_flux(f: &WindField, centre: &V3, axis: &V3, radius: f64, n: usize) -> f64 {
        let (e1, e2) = frame(axis);
        let dth = 2.0 * PI / n as f64;
        (0..n)
            .map(|k| {
                let th = k as f64 * dth;
                let normal = th.cos() * e1 + th.sin() * e2;
                f.velocity(&(centre + radius * normal), 0.0).dot(&normal) * radius * dth
            })
            .sum()
    }

    /// Gauss–Legendre nodes and weights on [−1, 1] (Newton on P_n).
    fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
        (0..n)
            .map(|i| {
                let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
                let mut dp = 0.0;
                for _ in 0..100 {
                    let (mut p0, mut p1) = (1.0, x);
                    for k in 2..=n {
                        let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                        p0 = p1;
                        p1 = p2;
                    }
                    dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                    let dx = p1 / dp;
                    x -= dx;
                    if dx.abs() < 1e-16 {
                        break;
                    }
                }
                (x, 2.0 / ((1.0 - x * x) * dp * dp))
            })
            .collect()
    }

    /// Outward flux through a sphere: Gauss–Legendre in cos θ, trapezoid in φ.
    fn sphere_flux(f: &WindField, centre: &V3, radius: f64) -> f64 {
        let nodes = gauss_legendre(48);
        let nphi = 96;
        let dphi = 2.0 * PI / nphi as f64;
        let mut total = 0.0;
        for &(mu, w) in &nodes {
            let s = (1.0 - mu * mu).sqrt();
            for k in 0..nphi {
                let phi = k as f64 * dphi;
                let n = v(s * phi.cos(), s * phi.sin(), mu);
                total += f.velocity(&(centre + radius * n), 0.0).dot(&n) * w * dphi;
            }
        }
        total * radius * radius
    }

    // ---- potential-flow identities (O8) ----

    #[test]
    fn divergence_and_curl_vanish_away_from_cores() {
        let axis = v(1.0, 2.0, 2.0);
        let tiny = 1e-9; // cores far smaller than any sample distance
        let fields: Vec<(&str, WindField)> = vec![
            (
                "uniform",
                WindField::new(vec![Primitive::uniform(v(1.0, -2.0, 0.5))]),
            ),
            (
                "point_source",
                WindField::new(vec![point_source(v(0.1, 0.2, 0.3), 1.7, tiny)]),
            ),
            (
                "line_source",
                WindField::new(vec![line_source(v(0.1, 0.2, 0.3), axis, 1.7, tiny)]),
            ),
            (
                "line_vortex lamb_oseen",
                WindField::new(vec![vortex(
                    v(0.1, 0.2, 0.3),
                    axis,
                    2.0,
                    0.01,
                    VortexCore::LambOseen,
                )]),
            ),
            (
                "line_vortex rankine",
                WindField::new(vec![vortex(
                    v(0.1, 0.2, 0.3),
                    axis,
                    2.0,
                    0.01,
                    VortexCore::Rankine,
                )]),
            ),
            (
                "superposition",
                WindField::new(vec![
                    Primitive::uniform(v(0.3, 0.0, 1.2)),
                    point_source(v(-0.5, 0.0, 0.0), -0.8, tiny),
                    line_source(v(0.5, 0.5, 0.0), v(0.0, 0.0, 1.0), 1.1, tiny),
                    vortex(
                        v(0.0, -0.5, 0.0),
                        v(0.0, 1.0, 1.0),
                        3.0,
                        0.01,
                        VortexCore::LambOseen,
                    ),
                ]),
            ),
        ];
        let samples = [
            v(1.0, 0.3, -0.7),
            v(-0.9, 1.4, 0.6),
            v(0.7, -1.1, 1.5),
            v(2.0, 2.0, -1.0),
        ];
        for (name, f) in &fields {
            for x in &samples {
                let g = |y: &V3| f.velocity(y, 0.0);
                let (div, curl) = div_curl(&g, x, 1e-5);
                // Scale |v|/ρ with ρ ~ 0.5 here: compare against a gradient scale of the field.
                let scale = f.speed_bound().min(10.0) + f.velocity(x, 0.0).norm();
                assert!(div.abs() < 1e-6 * scale, "{name} at {x:?}: div = {div}");
                assert!(
                    curl.norm() < 1e-6 * scale,
                    "{name} at {x:?}: curl = {curl:?}"
                );
                assert!(f.velocity(x, 0.0).norm() > 0.0);
            }
        }
    }

    #[test]
    fn smoothed_sources_have_the_exact_core_divergence() {
        // Line source: div = a ε²/(π(ρ² + ε²)²); point source: div = 3aε²/(4π(r² + ε²)^{5/2}).
        let (a, eps) = (1.7, 0.1);
        let axis = v(0.0, 0.0, 1.0);
        let line = WindField::new(vec![line_source(V3::zeros(), axis, a, eps)]);
        let point = WindField::new(vec![point_source(V3::zeros(), a, eps)]);
        for &rho in &[0.0, 0.03, 0.1, 0.25, 0.6] {
            let x = v(rho, 0.0, 0.4);
            let (div, curl) = div_curl(&|y: &V3| line.velocity(y, 0.0), &x, 1e-5);
            let exact = a * eps * eps / (PI * (rho * rho + eps * eps).powi(2));
            assert!(
                (div - exact).abs() < 1e-6 * exact.max(1.0),
                "line ρ={rho}: {div} vs {exact}"
            );
            assert!(curl.norm() < 1e-6);
            let x = v(rho, 0.0, 0.0);
            let (div, curl) = div_curl(&|y: &V3| point.velocity(y, 0.0), &x, 1e-5);
            let s = rho * rho + eps * eps;
            let exact = 3.0 * a * eps * eps / (4.0 * PI * s * s * s.sqrt());
            assert!(
                (div - exact).abs() < 1e-6 * exact.max(1.0),
                "point r={rho}: {div} vs {exact}"
            );
            assert!(curl.norm() < 1e-6);
        }
    }

    #[test]
    fn paper_source_formula_is_divergence_free_only_as_a_line_source() {
        // v = a/(2πr) r̂ with r the 3-D distance ("spherical", figure 2 read literally)
        // has div = a/(2πr²); with ρ the distance to an axis (our line_source) it is 0.
        let a = 1.3;
        let spherical = |x: &V3| x * (a / (2.0 * PI * x.norm_squared()));
        let line = WindField::new(vec![line_source(V3::zeros(), v(0.0, 0.0, 1.0), a, 1e-12)]);
        for x in [v(0.4, 0.3, 0.5), v(-0.2, 0.7, -1.5), v(1.0, 0.0, 3.0)] {
            let (div_sph, _) = div_curl(&spherical, &x, 1e-5);
            let expected = a / (2.0 * PI * x.norm_squared());
            assert!((div_sph - expected).abs() < 1e-6 * expected);
            assert!(div_sph > 0.01);
            let (div_line, _) = div_curl(&|y: &V3| line.velocity(y, 0.0), &x, 1e-5);
            assert!(div_line.abs() < 1e-7, "line source div {div_line} at {x:?}");
            // The line source has no component along its axis, however far along it we are.
            assert_eq!(line.velocity(&x, 0.0).z, 0.0);
        }
    }

    #[test]
    fn vortex_circulation_and_lamb_oseen_enclosed_circulation() {
        let gamma = 2.0;
        let axis = v(0.0, 1.0, 1.0);
        let p = v(0.2, -0.1, 0.3);
        for core in [VortexCore::LambOseen, VortexCore::Rankine] {
            let f = WindField::new(vec![vortex(p, axis, gamma, 1e-3, core)]);
            // Coaxial circle.
            let c = circulation(&f, &p, &axis, 0.5, 64);
            assert!((c - gamma).abs() < 1e-12, "{core:?}: {c}");
            // Off-centre circle that still encloses the axis.
            let (e1, _) = frame(&axis);
            let c = circulation(&f, &(p + 0.2 * e1), &axis, 0.5, 256);
            assert!((c - gamma).abs() < 1e-10, "{core:?} off-centre: {c}");
            // Circle not enclosing the axis.
            let c = circulation(&f, &(p + 1.0 * e1), &axis, 0.5, 256);
            assert!(c.abs() < 1e-10, "{core:?} not enclosing: {c}");
            // Sign: right-hand rule, reversed axis reverses the circulation.
            let f_rev = WindField::new(vec![vortex(p, -axis, gamma, 1e-3, core)]);
            assert!((circulation(&f_rev, &p, &axis, 0.5, 64) + gamma).abs() < 1e-12);
        }
        // Lamb–Oseen: circulation within ρ is Γ(1 − e^{−ρ²/r_c²}).
        let rc = 0.1;
        let f = WindField::new(vec![vortex(p, axis, gamma, rc, VortexCore::LambOseen)]);
        for rho in [0.02, 0.05, 0.1, 0.2, 0.3] {
            let c = circulation(&f, &p, &axis, rho, 64);
            let exact = gamma * (1.0 - (-(rho * rho) / (rc * rc)).exp());
            assert!((c - exact).abs() < 1e-13, "ρ={rho}: {c} vs {exact}");
        }
        // Rankine: solid body inside, Γρ²/R².
        let f = WindField::new(vec![vortex(p, axis, gamma, rc, VortexCore::Rankine)]);
        let c = circulation(&f, &p, &axis, 0.05, 64);
        assert!((c - gamma * 0.25).abs() < 1e-13);
    }

    #[test]
    fn source_fluxes_match_smoothed_closed_forms() {
        let a = 1.7;
        // Point source through a centred sphere: a R³/(R² + ε²)^{3/2}.
        let c = v(0.3, -0.2, 0.1);
        for (eps, r) in [(0.1, 0.5), (0.2, 0.1), (1e-6, 1.0)] {
            let f = WindField::new(vec![point_source(c, a, eps)]);
            let flux = sphere_flux(&f, &c, r);
            let exact = a * r.powi(3) / (r * r + eps * eps).powf(1.5);
            assert!(
                (flux - exact).abs() < 1e-12,
                "ε={eps} R={r}: {flux} vs {exact}"
            );
        }
        // Off-centre sphere enclosing a near-singular source: a (Gauss); not enclosing: 0.
        let f = WindField::new(vec![point_source(c, a, 1e-9)]);
        let flux = sphere_flux(&f, &(c + v(0.2, 0.1, 0.0)), 1.0);
        assert!((flux - a).abs() < 1e-9, "off-centre: {flux}");
        let flux = sphere_flux(&f, &(c + v(2.0, 0.0, 0.0)), 1.0);
        assert!(flux.abs() < 1e-10, "outside: {flux}");
        // Sink: positive strength means inflow.
        let sink = WindField::new(vec![Primitive::new(Flow::PointSink {
            point: c,
            flux: a,
            core_radius: 0.1,
        })]);
        let exact = a * 0.125 / (0.25f64 + 0.01).powf(1.5);
        assert!((sphere_flux(&sink, &c, 0.5) + exact).abs() < 1e-12);

        // Line source through a coaxial cylinder, per unit length: a R²/(R² + ε²).
        let axis = v(1.0, -1.0, 0.5);
        for (eps, r) in [(0.1, 0.5), (0.3, 0.1), (1e-9, 1.0)] {
            let f = WindField::new(vec![line_source(c, axis, a, eps)]);
            let flux = ring_flux(&f, &(c + 3.0 * axis), &axis, r, 64);
            let exact = a * r * r / (r * r + eps * eps);
            assert!(
                (flux - exact).abs() < 1e-12,
                "ε={eps} R={r}: {flux} vs {exact}"
            );
        }
        let f = WindField::new(vec![Primitive::new(Flow::LineSink {
            point: c,
            axis,
            flux: a,
            core_radius: 1e-9,
        })]);
        let (e1, _) = frame(&axis);
        assert!((ring_flux(&f, &(c + 0.3 * e1), &axis, 1.0, 256) + a).abs() < 1e-10);
        assert!(ring_flux(&f, &(c + 2.0 * e1), &axis, 1.0, 256).abs() < 1e-10);
    }

    // ---- superposition ----

    fn coord() -> impl Strategy<Value = f64> {
        -2.0..2.0f64
    }

    proptest! {
        #[test]
        fn superposition_is_linear(
            x in (coord(), coord(), coord()),
            s1 in -5.0..5.0f64,
            s2 in -5.0..5.0f64,
            u in (coord(), coord(), coord()),
            t in -1.0..4.0f64,
        ) {
            let x = v(x.0, x.1, x.2);
            let u = v(u.0, u.1, u.2);
            let p = v(0.1, -0.3, 0.2);
            let axis = v(0.3, 0.4, 1.0);
            let make = |s: f64| -> Vec<Primitive> {
                vec![
                    Primitive::uniform(u * s),
                    point_source(p, s, 0.05),
                    line_source(p, axis, s, 0.05),
                    vortex(p, axis, s, 0.05, VortexCore::LambOseen),
                    vortex(-p, axis, s, 0.05, VortexCore::Rankine),
                ]
            };
            let keys = Keyframes { keys: vec![(0.0, 0.5), (2.0, 1.5)], interpolation: Interpolation::Linear };
            let bounds = Bounds { region: Region::Sphere { center: p, radius: 0.5 }, falloff: 1.0 };
            let with = |ps: Vec<Primitive>| -> Vec<Primitive> {
                ps.into_iter().map(|q| q.with_keys(keys.clone()).with_bounds(bounds.clone())).collect()
            };
            let a = WindField::new(with(make(s1)));
            let b = WindField::new(with(make(s2)));
            let sum = WindField::new(with(make(s1 + s2)));
            let both = WindField::new(with(make(s1)).into_iter().chain(with(make(s2))).collect());
            let (ga, gb) = (a.velocity(&x, t), b.velocity(&x, t));
            let tol = 1e-12 * (1.0 + a.speed_bound() + b.speed_bound());
            // Field of the sum of strengths = sum of fields.
            prop_assert!((sum.velocity(&x, t) - (ga + gb)).norm() < tol);
            // Field of the union of primitives = sum of fields.
            prop_assert!((both.velocity(&x, t) - (ga + gb)).norm() < tol);
            // And each field is the sum of its primitives.
            let parts: V3 = a.primitives().iter().map(|q| q.velocity(&x, t)).sum();
            prop_assert!((a.velocity(&x, t) - parts).norm() < tol);
            prop_assert!(a.velocity(&x, t).norm() <= a.speed_bound() * (1.0 + 1e-12));
        }
    }

    // ---- regularised cores (O9, §4) ----

    #[test]
    fn cores_are_finite_and_zero_on_the_axis() {
        let p = v(0.1, 0.2, -0.3);
        let axis = v(0.0, 1.0, 1.0);
        let prims = [
            point_source(p, 2.0, 0.05),
            line_source(p, axis, 2.0, 0.05),
            vortex(p, axis, 2.0, 0.05, VortexCore::LambOseen),
            vortex(p, axis, 2.0, 0.05, VortexCore::Rankine),
        ];
        for q in &prims {
            let f = WindField::new(vec![q.clone()]);
            // Exactly at the point / on the axis (several points along it).
            let along: &[f64] = match q.flow() {
                Flow::PointSource { .. } => &[0.0],
                _ => &[0.0, 0.5, -2.0],
            };
            for &s in along {
                let on_axis = p + s * axis;
                let g = f.velocity(&on_axis, 0.0);
                if s == 0.0 {
                    assert_eq!(g, V3::zeros(), "{:?}", q.flow());
                }
                // Elsewhere on the axis only round-off in ρ remains.
                assert!(g.norm() < 1e-12 * f.speed_bound(), "{:?}: {g:?}", q.flow());
            }
            // A grid through the core, including the axis.
            for i in -10..=10 {
                for j in -10..=10 {
                    let x = p + v(i as f64 * 0.01, j as f64 * 0.01, 0.0);
                    let g = f.velocity(&x, 0.0);
                    assert!(g.iter().all(|c| c.is_finite()));
                    assert!(g.norm() <= f.speed_bound() * (1.0 + 1e-12));
                }
            }
        }
        // Near the Taylor switch of (1 − e^{−q})/q the vortex stays smooth.
        let below = one_minus_exp_over(1e-6 * (1.0 - 1e-9));
        let above = one_minus_exp_over(1e-6 * (1.0 + 1e-9));
        assert!((below - above).abs() < 1e-14);
        assert_eq!(one_minus_exp_over(0.0), 1.0);
    }

    /// Tangential speed of a z-axis vortex at distance ρ.
    fn v_theta(f: &WindField, rho: f64) -> f64 {
        f.velocity(&v(rho, 0.0, 0.7), 0.0).y
    }

    #[test]
    fn lamb_oseen_peak_and_far_field() {
        let (gamma, rc) = (2.0, 0.05);
        let f = WindField::new(vec![vortex(
            V3::zeros(),
            V3::z(),
            gamma,
            rc,
            VortexCore::LambOseen,
        )]);
        // Golden-section search for the peak.
        let (mut lo, mut hi) = (0.5 * rc, 2.0 * rc);
        let g = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..100 {
            let (a, b) = (hi - g * (hi - lo), lo + g * (hi - lo));
            if v_theta(&f, a) > v_theta(&f, b) {
                hi = b;
            } else {
                lo = a;
            }
        }
        let rho_max = 0.5 * (lo + hi);
        assert!(
            (rho_max / rc - 1.1209).abs() < 1e-4,
            "peak at {}",
            rho_max / rc
        );
        let vmax = v_theta(&f, rho_max) / (gamma / (2.0 * PI * rc));
        assert!((vmax - 0.6382).abs() < 1e-4, "v_max ratio {vmax}");
        // speed_bound is that peak, from above.
        let exact_peak = v_theta(&f, rho_max);
        assert!(f.speed_bound() >= exact_peak && f.speed_bound() < exact_peak * (1.0 + 1e-6));
        // Far field: the singular Γ/(2πρ).
        for rho in [10.0 * rc, 30.0 * rc, 1e3 * rc] {
            let singular = gamma / (2.0 * PI * rho);
            assert!((v_theta(&f, rho) - singular).abs() < 1e-12 * singular);
        }
    }

    #[test]
    fn rankine_core_is_continuous_and_exact_outside() {
        let (gamma, r) = (2.0, 0.05);
        let f = WindField::new(vec![vortex(
            V3::zeros(),
            V3::z(),
            gamma,
            r,
            VortexCore::Rankine,
        )]);
        let at_r = gamma / (2.0 * PI * r);
        assert!((v_theta(&f, r) - at_r).abs() < 1e-12 * at_r);
        for d in [1e-3, 1e-6, 1e-9] {
            let jump = (v_theta(&f, r * (1.0 + d)) - v_theta(&f, r * (1.0 - d))).abs();
            assert!(jump < 2.0 * d * at_r, "jump {jump} at δ={d}");
        }
        // Solid-body rotation inside, free vortex outside.
        assert!((v_theta(&f, 0.4 * r) - 0.4 * at_r).abs() < 1e-12 * at_r);
        for rho in [1.5 * r, 20.0 * r] {
            let singular = gamma / (2.0 * PI * rho);
            assert!((v_theta(&f, rho) - singular).abs() < 1e-14 * singular);
        }
        assert!((f.speed_bound() - at_r).abs() < 1e-12 * at_r);
        // Right-hand rule: +Γ about +z at +x points along +y.
        assert!(v_theta(&f, 0.3) > 0.0);
    }

    #[test]
    fn smoothed_sources_match_singular_far_field_and_speed_bound() {
        let (a, eps) = (1.5, 0.01);
        let line = WindField::new(vec![line_source(V3::zeros(), V3::z(), a, eps)]);
        let point = WindField::new(vec![point_source(V3::zeros(), a, eps)]);
        for rho in [1.0, 3.0] {
            let exact = a / (2.0 * PI * rho);
            let got = line.velocity(&v(rho, 0.0, 5.0), 0.0).x;
            assert!((got - exact).abs() < 2.0 * (eps / rho).powi(2) * exact);
            let exact = a / (4.0 * PI * rho * rho);
            let got = point.velocity(&v(0.0, 0.0, rho), 0.0).z;
            assert!((got - exact).abs() < 3.0 * (eps / rho).powi(2) * exact);
        }
        // Peaks: line source at ρ = ε, point source at r = ε/√2.
        let line_peak = line.velocity(&v(eps, 0.0, 0.0), 0.0).norm();
        assert!((line.speed_bound() - line_peak).abs() < 1e-12 * line_peak);
        let point_peak = point.velocity(&v(eps / 2f64.sqrt(), 0.0, 0.0), 0.0).norm();
        assert!((point.speed_bound() - point_peak).abs() < 1e-12 * point_peak);
        for k in 1..200 {
            let r = k as f64 * 1e-4;
            assert!(line.velocity(&v(r, 0.0, 0.0), 0.0).norm() <= line_peak * (1.0 + 1e-12));
            assert!(point.velocity(&v(r, 0.0, 0.0), 0.0).norm() <= point_peak * (1.0 + 1e-12));
        }
    }

    #[test]
    fn rankine_half_body_stagnation_point() {
        // Uniform U along +x plus a line source a on the z axis: stagnation at x = −a/(2πU).
        let (u, a) = (1.2, 0.9);
        let f = WindField::new(vec![
            Primitive::uniform(v(u, 0.0, 0.0)),
            line_source(V3::zeros(), V3::z(), a, 1e-9),
        ]);
        let xs = -a / (2.0 * PI * u);
        assert!(f.velocity(&v(xs, 0.0, 0.4), 0.0).norm() < 1e-12 * u);
        // Flow reaches it from upstream and is pushed back from the source side.
        assert!(f.velocity(&v(xs * 1.01, 0.0, 0.0), 0.0).x > 0.0);
        assert!(f.velocity(&v(xs * 0.99, 0.0, 0.0), 0.0).x < 0.0);
        // Far downstream the source's flux a spreads over a body of half-width a/(2U):
        // on the body's asymptote the wind is U again.
        let far = f.velocity(&v(1e7, a / (2.0 * u), 0.0), 0.0);
        assert!((far - v(u, 0.0, 0.0)).norm() < 1e-7);
    }

    // ---- tracers (O10) ----

    #[test]
    fn rk4_tracer_stays_on_its_circle() {
        let gamma = 2.0;
        let axis = v(1.0, 2.0, 2.0) / 3.0;
        let p = v(0.3, -0.1, 0.2);
        let f = WindField::new(vec![vortex(p, axis, gamma, 0.01, VortexCore::LambOseen)]);
        let (e1, _) = frame(&axis);
        let rho = 0.3;
        let x0 = p + rho * e1 + 0.5 * axis;
        let omega = gamma / (2.0 * PI * rho * rho);
        let period = 2.0 * PI / omega;
        let n = 2000;
        let h = period / n as f64;
        let mut x = x0;
        let mut t = 0.0;
        let mut max_drift: f64 = 0.0;
        for k in 0..n {
            let k1 = f.velocity(&x, t);
            let k2 = f.velocity(&(x + 0.5 * h * k1), t + 0.5 * h);
            let k3 = f.velocity(&(x + 0.5 * h * k2), t + 0.5 * h);
            let k4 = f.velocity(&(x + h * k3), t + h);
            x += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
            t = (k + 1) as f64 * h;
            let d = x - p;
            let r = (d - axis * axis.dot(&d)).norm();
            max_drift = max_drift.max((r - rho).abs());
            // Quarter turn: angle ωt.
            if k + 1 == n / 4 {
                let (e1, e2) = frame(&axis);
                let ang = (d.dot(&e2)).atan2(d.dot(&e1));
                assert!((ang - omega * t).abs() < 1e-10, "{ang} vs {}", omega * t);
            }
        }
        assert!(max_drift < 1e-11 * rho, "radius drift {max_drift}");
        assert!((x - x0).norm() < 1e-10, "after one period {:?}", x - x0);
    }

    #[test]
    fn forward_euler_tracer_spirals_out_discrete_exactly() {
        // O10: ρ²_{n+1} = ρ²_n + (hΓ/(2πρ_n))² outside the core.
        let gamma = 2.0;
        let f = WindField::new(vec![vortex(
            V3::zeros(),
            V3::z(),
            gamma,
            1e-3,
            VortexCore::Rankine,
        )]);
        let h = 0.01;
        let mut x = v(0.3, 0.0, 0.0);
        let mut rho2 = 0.09f64;
        for _ in 0..200 {
            x += h * f.velocity(&x, 0.0);
            rho2 += (h * gamma / (2.0 * PI * rho2.sqrt())).powi(2);
            let got = x.x * x.x + x.y * x.y;
            assert!((got - rho2).abs() < 1e-13 * rho2);
        }
        assert!(rho2 > 0.09 * 1.01);
    }

    // ---- bounds and fronts ----

    #[test]
    fn sphere_bounds_weight() {
        let c = v(0.5, 0.0, 1.0);
        let u = v(0.0, 0.0, 2.0);
        let f = WindField::new(vec![Primitive::uniform(u).with_bounds(Bounds {
            region: Region::Sphere {
                center: c,
                radius: 1.0,
            },
            falloff: 0.5,
        })]);
        let dir = v(1.0, 2.0, -2.0) / 3.0;
        let at = |d: f64| f.velocity(&(c + d * dir), 0.0);
        assert_eq!(at(0.0), u);
        assert_eq!(at(0.99), u);
        assert_eq!(at(1.0), u);
        assert!((at(1.25) - 0.5 * u).norm() < 1e-12);
        assert_eq!(at(1.5), V3::zeros());
        assert_eq!(at(1.5 + 1e-12), V3::zeros());
        assert_eq!(at(100.0), V3::zeros());
        // Continuous: steps of 1e-5 never jump more than max slope (15/8)/falloff × step.
        let step = 1e-5;
        let mut prev = at(0.9);
        let mut d = 0.9;
        while d < 1.6 {
            d += step;
            let cur = at(d);
            assert!((cur - prev).norm() <= 2.0 * 1.875 / 0.5 * step * (1.0 + 1e-9));
            prev = cur;
        }
        // Strictly between full and zero inside the band, and decreasing.
        assert!(at(1.1).z < u.z && at(1.1).z > at(1.4).z && at(1.4).z > 0.0);
    }

    #[test]
    fn box_and_cylinder_bounds_weight() {
        let vort = vortex(V3::zeros(), V3::z(), 2.0, 0.01, VortexCore::LambOseen);
        let unbounded = WindField::new(vec![vort.clone()]);
        let boxed = WindField::new(vec![vort.clone().with_bounds(Bounds {
            region: Region::Box {
                min: v(-1.0, -1.0, 0.0),
                max: v(1.0, 1.0, 2.0),
            },
            falloff: 0.2,
        })]);
        // Deep inside: unchanged.
        for x in [v(0.5, 0.0, 1.0), v(-0.9, 0.9, 0.1), v(1.0, 0.3, 2.0)] {
            assert_eq!(boxed.velocity(&x, 0.0), unbounded.velocity(&x, 0.0));
        }
        // Beyond a face, edge or corner by the falloff: exactly 0.
        for x in [
            v(1.2001, 0.0, 1.0),
            v(0.0, 0.0, -0.2001),
            v(1.15, 1.15, 1.0),
            v(1.2, 1.2, 2.2),
        ] {
            assert_eq!(boxed.velocity(&x, 0.0), V3::zeros(), "{x:?}");
        }
        // Halfway through the band beyond a face: w = 1/2; near a corner the distance is Euclidean.
        let x = v(1.1, 0.0, 1.0);
        assert!((boxed.velocity(&x, 0.0) - 0.5 * unbounded.velocity(&x, 0.0)).norm() < 1e-12);
        let s = 0.1 / 2f64.sqrt();
        let x = v(1.0 + s, 1.0 + s, 1.0);
        assert!((boxed.velocity(&x, 0.0) - 0.5 * unbounded.velocity(&x, 0.0)).norm() < 1e-12);

        let tube = WindField::new(vec![Primitive::uniform(v(1.0, 0.0, 0.0)).with_bounds(
            Bounds {
                region: Region::Cylinder {
                    point: V3::zeros(),
                    axis: v(0.0, 0.0, 3.0),
                    radius: 0.5,
                },
                falloff: 0.1,
            },
        )]);
        assert_eq!(tube.velocity(&v(0.3, 0.3, 100.0), 0.0).x, 1.0);
        assert!((tube.velocity(&v(0.0, 0.55, -7.0), 0.0).x - 0.5).abs() < 1e-12);
        assert_eq!(tube.velocity(&v(0.6001, 0.0, 0.0), 0.0).x, 0.0);
        // A hard edge when falloff = 0.
        let hard = WindField::new(vec![Primitive::uniform(v(1.0, 0.0, 0.0)).with_bounds(
            Bounds {
                region: Region::Sphere {
                    center: V3::zeros(),
                    radius: 1.0,
                },
                falloff: 0.0,
            },
        )]);
        assert_eq!(hard.velocity(&v(1.0, 0.0, 0.0), 0.0).x, 1.0);
        assert_eq!(hard.velocity(&v(1.0 + 1e-9, 0.0, 0.0), 0.0).x, 0.0);
    }

    #[test]
    fn moving_front_sweeps_at_its_speed() {
        // Plane z = −1 + 2t (normal given unnormalised), falloff 0.1 ahead of it.
        let front = Front {
            normal: v(0.0, 0.0, 2.0),
            offset: -1.0,
            speed: 2.0,
            falloff: 0.1,
        };
        assert_eq!(front.offset_at(1.5), 2.0);
        let up = v(0.0, 0.0, 3.0);
        let f = WindField::new(vec![Primitive::uniform(up).with_front(front.clone())]);
        let t = 1.5;
        assert_eq!(f.velocity(&v(4.0, -2.0, 1.0), t), up);
        assert_eq!(f.velocity(&v(0.0, 0.0, 2.0), t), up);
        assert!((f.velocity(&v(0.0, 0.0, 2.05), t) - 0.5 * up).norm() < 1e-12);
        assert_eq!(f.velocity(&v(0.0, 0.0, 2.1), t), V3::zeros());
        // A leaf at z = 1 sees nothing at t = 0, then full wind once the front passes (t ≥ 1).
        let leaf = v(0.2, 0.2, 1.0);
        assert_eq!(f.velocity(&leaf, 0.0), V3::zeros());
        assert_eq!(f.velocity(&leaf, 0.95 - 1e-9), V3::zeros());
        assert!(f.velocity(&leaf, 0.975).z > 0.0 && f.velocity(&leaf, 0.975).z < up.z);
        assert_eq!(f.velocity(&leaf, 1.0), up);
        // Composes with a singular primitive, bounds and keys: all weights multiply.
        let vort = vortex(V3::zeros(), V3::z(), 2.0, 0.01, VortexCore::Rankine);
        let x = v(0.3, 0.0, 2.05);
        let plain = vort.velocity(&x, t);
        let gated = vort
            .clone()
            .with_front(front)
            .with_bounds(Bounds {
                region: Region::Sphere {
                    center: V3::zeros(),
                    radius: 0.1,
                },
                falloff: 4.0,
            })
            .with_keys(Keyframes {
                keys: vec![(0.0, 3.0)],
                interpolation: Interpolation::Step,
            });
        let d = x.norm() - 0.1;
        let expected = plain * 0.5 * falloff_weight(d, 4.0) * 3.0;
        assert!((gated.velocity(&x, t) - expected).norm() < 1e-12 * plain.norm());
        assert!(falloff_weight(d, 4.0) > 0.0 && falloff_weight(d, 4.0) < 1.0);
    }

    // ---- keyframes ----

    #[test]
    fn keyframe_interpolation() {
        let keys = vec![(0.0, 0.0), (1.0, 1.0), (3.0, 0.2)];
        let lin = Keyframes {
            keys: keys.clone(),
            interpolation: Interpolation::Linear,
        };
        let step = Keyframes {
            keys,
            interpolation: Interpolation::Step,
        };
        let cases = [
            (-5.0, 0.0, 0.0),
            (0.0, 0.0, 0.0),
            (0.25, 0.25, 0.0),
            (1.0, 1.0, 1.0),
            (2.0, 0.6, 1.0),
            (2.999, 1.0 - 0.8 * 0.9995, 1.0),
            (3.0, 0.2, 0.2),
            (50.0, 0.2, 0.2),
        ];
        for (t, l, s) in cases {
            assert!(
                (lin.value(t) - l).abs() < 1e-12,
                "linear t={t}: {}",
                lin.value(t)
            );
            assert_eq!(step.value(t), s, "step t={t}");
        }
        let single = Keyframes {
            keys: vec![(2.0, 0.7)],
            interpolation: Interpolation::Linear,
        };
        assert_eq!(single.value(-1.0), 0.7);
        assert_eq!(single.value(9.0), 0.7);
        assert_eq!(lin.max_abs(), 1.0);
        // Applied to a primitive, and to its speed bound.
        let u = v(1.0, 2.0, 0.0);
        let p = Primitive::uniform(u).with_keys(lin);
        assert!((p.velocity(&V3::zeros(), 2.0) - 0.6 * u).norm() < 1e-12);
        assert_eq!(p.velocity(&V3::zeros(), -1.0), V3::zeros());
        assert!((p.speed_bound() - u.norm()).abs() < 1e-15);
    }

    // ---- validation ----

    fn item_of(p: Primitive) -> String {
        let f = WindField::new(vec![Primitive::uniform(v(1.0, 0.0, 0.0)), p]);
        let e = f.validate().expect_err("should be invalid");
        assert!(!e.reason.is_empty());
        assert_eq!(e.to_string(), format!("{}: {}", e.item, e.reason));
        e.item
    }

    #[test]
    fn validation_names_the_item() {
        let p = V3::zeros();
        let z = V3::z();
        let nan = f64::NAN;
        let inf = f64::INFINITY;
        let sphere = |radius: f64, falloff: f64| Bounds {
            region: Region::Sphere { center: p, radius },
            falloff,
        };
        let front = |normal: V3, offset: f64, speed: f64, falloff: f64| Front {
            normal,
            offset,
            speed,
            falloff,
        };
        let keyed = |keys: Vec<(f64, f64)>| {
            Primitive::uniform(z).with_keys(Keyframes {
                keys,
                interpolation: Interpolation::Linear,
            })
        };
        let line_sink = |axis: V3, core_radius: f64| {
            Primitive::new(Flow::LineSink {
                point: p,
                axis,
                flux: 1.0,
                core_radius,
            })
        };
        let cases: Vec<(Primitive, &str)> = vec![
            (Primitive::uniform(v(nan, 0.0, 0.0)), "wind[1].velocity"),
            (point_source(v(0.0, inf, 0.0), 1.0, 0.1), "wind[1].point"),
            (point_source(p, nan, 0.1), "wind[1].flux"),
            (point_source(p, 1.0, 0.0), "wind[1].core_radius"),
            (point_source(p, 1.0, -0.1), "wind[1].core_radius"),
            (point_source(p, 1.0, nan), "wind[1].core_radius"),
            (line_sink(z, 0.0), "wind[1].core_radius"),
            (line_sink(V3::zeros(), 0.1), "wind[1].axis"),
            (line_sink(v(inf, 0.0, 0.0), 0.1), "wind[1].axis"),
            (line_source(p, v(0.0, nan, 1.0), 1.0, 0.1), "wind[1].axis"),
            (
                vortex(p, z, inf, 0.1, VortexCore::Rankine),
                "wind[1].circulation",
            ),
            (
                vortex(p, z, 1.0, -1.0, VortexCore::LambOseen),
                "wind[1].core_radius",
            ),
            (
                vortex(p, V3::zeros(), 1.0, 0.1, VortexCore::LambOseen),
                "wind[1].axis",
            ),
            (
                Primitive::uniform(z).with_bounds(sphere(-1.0, 0.1)),
                "wind[1].bounds.radius",
            ),
            (
                Primitive::uniform(z).with_bounds(sphere(1.0, -0.1)),
                "wind[1].bounds.falloff",
            ),
            (
                Primitive::uniform(z).with_bounds(sphere(1.0, nan)),
                "wind[1].bounds.falloff",
            ),
            (
                Primitive::uniform(z).with_bounds(Bounds {
                    region: Region::Sphere {
                        center: v(nan, 0.0, 0.0),
                        radius: 1.0,
                    },
                    falloff: 0.1,
                }),
                "wind[1].bounds.center",
            ),
            (
                Primitive::uniform(z).with_bounds(Bounds {
                    region: Region::Box {
                        min: v(0.0, 2.0, 0.0),
                        max: v(1.0, 1.0, 1.0),
                    },
                    falloff: 0.1,
                }),
                "wind[1].bounds.min",
            ),
            (
                Primitive::uniform(z).with_bounds(Bounds {
                    region: Region::Cylinder {
                        point: p,
                        axis: V3::zeros(),
                        radius: 1.0,
                    },
                    falloff: 0.1,
                }),
                "wind[1].bounds.axis",
            ),
            (
                Primitive::uniform(z).with_bounds(Bounds {
                    region: Region::Cylinder {
                        point: p,
                        axis: z,
                        radius: -2.0,
                    },
                    falloff: 0.1,
                }),
                "wind[1].bounds.radius",
            ),
            (
                Primitive::uniform(z).with_front(front(V3::zeros(), 0.0, 1.0, 0.1)),
                "wind[1].front.normal",
            ),
            (
                Primitive::uniform(z).with_front(front(z, nan, 1.0, 0.1)),
                "wind[1].front.offset",
            ),
            (
                Primitive::uniform(z).with_front(front(z, 0.0, inf, 0.1)),
                "wind[1].front.speed",
            ),
            (
                Primitive::uniform(z).with_front(front(z, 0.0, 1.0, -0.1)),
                "wind[1].front.falloff",
            ),
            (keyed(vec![]), "wind[1].keys"),
            (
                keyed(vec![(0.0, 1.0), (2.0, 1.0), (1.0, 0.0)]),
                "wind[1].keys[2]",
            ),
            (keyed(vec![(0.0, 1.0), (0.0, 2.0)]), "wind[1].keys[1]"),
            (keyed(vec![(0.0, 1.0), (1.0, nan)]), "wind[1].keys[1]"),
            (keyed(vec![(nan, 1.0)]), "wind[1].keys[0]"),
        ];
        for (prim, item) in cases {
            assert_eq!(item_of(prim), item);
        }
        // And a valid field of every kind passes.
        assert!(sample_field().validate().is_ok());
        assert!(WindField::still().validate().is_ok());
    }

    // ---- TOML ----

    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Scene {
        wind: WindField,
    }

    const SAMPLE: &str = r#"
[[wind]]
kind = "uniform"
velocity = [0.0, 0.0, 1.2]
keys = [[0.0, 0.0], [1.0, 1.0], [3.0, 0.2]]
interpolation = "step"
[wind.front]
normal = [0.0, 0.0, 1.0]
offset = -1.0
speed = 2.0
falloff = 0.1

[[wind]]
kind = "line_vortex"
point = [0.0, 0.0, 0.0]
axis = [0.0, 0.0, 2.0]
circulation = 2.0
core_radius = 0.05
core = "rankine"
bounds = { shape = "cylinder", point = [0.0, 0.0, 0.0], axis = [0.0, 0.0, 1.0], radius = 1.0, falloff = 0.5 }

[[wind]]
kind = "line_vortex"
point = [1.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
circulation = -1.0
core_radius = 0.05

[[wind]]
kind = "point_source"
point = [0.0, 1.0, 0.0]
flux = 0.5
core_radius = 0.02
[wind.bounds]
shape = "sphere"
center = [0.0, 1.0, 0.0]
radius = 0.5
falloff = 0.25

[[wind]]
kind = "point_sink"
point = [0.0, -1.0, 0.0]
flux = 0.5
core_radius = 0.02

[[wind]]
kind = "line_source"
point = [2.0, 0.0, 0.0]
axis = [1.0, 1.0, 0.0]
flux = 0.3
core_radius = 0.01
bounds = { shape = "box", min = [-1.0, -1.0, 0.0], max = [1.0, 1.0, 3.0], falloff = 0.2 }

[[wind]]
kind = "line_sink"
point = [0.0, 0.0, 5.0]
axis = [1.0, 0.0, 0.0]
flux = 0.3
core_radius = 0.01
keys = [[0.0, 1.0], [2.0, 0.0]]
"#;

    fn sample_field() -> WindField {
        toml::from_str::<Scene>(SAMPLE).expect("sample parses").wind
    }

    #[test]
    fn toml_round_trip() {
        let f = sample_field();
        f.validate().unwrap();
        assert_eq!(f.primitives().len(), 7);
        assert!(!f.is_still());
        // Parsed as intended: default core, default interpolation, unnormalised axes kept.
        match f.primitives()[2].flow() {
            Flow::LineVortex { core, .. } => assert_eq!(*core, VortexCore::LambOseen),
            other => panic!("{other:?}"),
        }
        assert_eq!(
            f.primitives()[6].keys().unwrap().interpolation,
            Interpolation::Linear
        );
        match f.primitives()[1].flow() {
            Flow::LineVortex { axis, .. } => assert_eq!(*axis, v(0.0, 0.0, 2.0)),
            other => panic!("{other:?}"),
        }
        // Same field as built in Rust.
        let built = vortex(
            V3::zeros(),
            v(0.0, 0.0, 2.0),
            2.0,
            0.05,
            VortexCore::Rankine,
        )
        .with_bounds(Bounds {
            region: Region::Cylinder {
                point: V3::zeros(),
                axis: z_axis(),
                radius: 1.0,
            },
            falloff: 0.5,
        });
        assert_eq!(f.primitives()[1], built);
        let scene = Scene { wind: f.clone() };
        let text = toml::to_string(&scene).unwrap();
        let back: Scene = toml::from_str(&text).unwrap();
        assert_eq!(back, scene, "{text}");
        // Velocities agree after the round trip.
        for x in [v(0.3, 0.2, 0.1), v(-0.5, 1.1, 2.0)] {
            assert_eq!(back.wind.velocity(&x, 1.3), f.velocity(&x, 1.3));
        }
        // Still air round trips as an empty array.
        let still = Scene {
            wind: WindField::still(),
        };
        let back: Scene = toml::from_str(&toml::to_string(&still).unwrap()).unwrap();
        assert!(back.wind.is_still());
    }

    fn z_axis() -> V3 {
        V3::z()
    }

    #[test]
    fn toml_rejects_unknown_and_misplaced_keys() {
        let bad = [
            // Unknown key on a primitive.
            "[[wind]]\nkind = \"uniform\"\nvelocity = [1.0, 0.0, 0.0]\nvelocty = [1.0, 0.0, 0.0]\n",
            // Key of another kind.
            "[[wind]]\nkind = \"uniform\"\nvelocity = [1.0, 0.0, 0.0]\ncirculation = 1.0\n",
            "[[wind]]\nkind = \"point_source\"\npoint = [0.0, 0.0, 0.0]\nflux = 1.0\ncore_radius = 0.1\naxis = [0.0, 0.0, 1.0]\n",
            "[[wind]]\nkind = \"line_source\"\npoint = [0.0, 0.0, 0.0]\naxis = [0.0, 0.0, 1.0]\nflux = 1.0\ncore_radius = 0.1\ncore = \"rankine\"\n",
            // Missing required key.
            "[[wind]]\nkind = \"line_vortex\"\npoint = [0.0, 0.0, 0.0]\naxis = [0.0, 0.0, 1.0]\ncirculation = 1.0\n",
            // Unknown kind, core, interpolation.
            "[[wind]]\nkind = \"tornado\"\n",
            "[[wind]]\nkind = \"line_vortex\"\npoint = [0.0, 0.0, 0.0]\naxis = [0.0, 0.0, 1.0]\ncirculation = 1.0\ncore_radius = 0.1\ncore = \"scully\"\n",
            "[[wind]]\nkind = \"uniform\"\nvelocity = [1.0, 0.0, 0.0]\nkeys = [[0.0, 1.0]]\ninterpolation = \"cubic\"\n",
            // Interpolation without keys.
            "[[wind]]\nkind = \"uniform\"\nvelocity = [1.0, 0.0, 0.0]\ninterpolation = \"step\"\n",
            // Unknown or misplaced keys in bounds and front.
            "[[wind]]\nkind = \"uniform\"\nvelocity = [1.0, 0.0, 0.0]\nbounds = { shape = \"sphere\", center = [0.0, 0.0, 0.0], radius = 1.0, falloff = 0.1, power = 2.0 }\n",
            "[[wind]]\nkind = \"uniform\"\nvelocity = [1.0, 0.0, 0.0]\nbounds = { shape = \"sphere\", center = [0.0, 0.0, 0.0], radius = 1.0, falloff = 0.1, min = [0.0, 0.0, 0.0] }\n",
            "[[wind]]\nkind = \"uniform\"\nvelocity = [1.0, 0.0, 0.0]\nbounds = { shape = \"sphere\", center = [0.0, 0.0, 0.0], radius = 1.0 }\n",
            "[[wind]]\nkind = \"uniform\"\nvelocity = [1.0, 0.0, 0.0]\n[wind.front]\nnormal = [0.0, 0.0, 1.0]\noffset = 0.0\nfalloff = 0.1\nsped = 1.0\n",
            // Wrong shape of a vector.
            "[[wind]]\nkind = \"uniform\"\nvelocity = [1.0, 0.0]\n",
        ];
        for text in bad {
            let r = toml::from_str::<Scene>(text);
            assert!(r.is_err(), "accepted:\n{text}");
        }
        // The same tables without the offending key parse.
        let good = "[[wind]]\nkind = \"uniform\"\nvelocity = [1.0, 0.0, 0.0]\n[wind.front]\nnormal = [0.0, 0.0, 1.0]\noffset = 0.0\nfalloff = 0.1\n";
        let s: Scene = toml::from_str(good).unwrap();
        assert_eq!(s.wind.primitives()[0].front().unwrap().speed, 0.0);
        let err = toml::from_str::<Scene>(bad[0]).unwrap_err().to_string();
        assert!(err.contains("velocty"), "{err}");
        let err = toml::from_str::<Scene>(bad[1]).unwrap_err().to_string();
        assert!(
            err.contains("circulation") && err.contains("uniform"),
            "{err}"
        );
    }

    #[test]
    fn still_air() {
        let f = WindField::still();
        assert!(f.is_still());
        assert_eq!(f.velocity(&v(1.0, 2.0, 3.0), 4.0), V3::zeros());
        assert_eq!(f.speed_bound(), 0.0);
        assert!(!WindField::new(vec![Primitive::uniform(V3::zeros())]).is_still());
    }
}
