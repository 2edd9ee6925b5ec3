//! One wind primitive: a flow, optionally bounded, gated by a moving front
//! and scaled by keyframes; and its `[[wind]]` table.

use nalgebra::Vector3;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::bounds::{Bounds, BoundsSpec, RegionEval};
use super::error::FieldError;
use super::flows::{Flow, FlowEval, FlowKeys, Kind, Uniform, VortexCore};
use super::front::{Front, FrontEval, FrontSpec};
use super::keys::{Interpolation, Keyframes};

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
        Self::new(Flow::Uniform(Uniform { velocity }))
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

    /// Whether this primitive can be nonzero somewhere in the box [lo, hi]
    /// at time `t` (corners finite). False only when [`Primitive::velocity`]
    /// returns exact zeros at every point of the box: its keys are 0 at `t`,
    /// or the box lies wholly beyond its bounds' falloff band or ahead of its
    /// front's band, so the gain k · w_bounds · w_front is 0 (every factor is
    /// finite at finite points).
    #[inline]
    pub fn reaches_box(&self, lo: &Vector3<f64>, hi: &Vector3<f64>, t: f64) -> bool {
        self.unreached_box(lo, hi, t).is_none()
    }

    /// Why this primitive cannot reach the box [lo, hi] at time `t` (as
    /// [`Primitive::reaches_box`]), or `None` when it may.
    #[inline]
    pub fn unreached_box(
        &self,
        lo: &Vector3<f64>,
        hi: &Vector3<f64>,
        t: f64,
    ) -> Option<&'static str> {
        if self.keys.as_ref().is_some_and(|k| k.value(t) == 0.0) {
            return Some("its keys are 0");
        }
        if self
            .compiled
            .region
            .as_ref()
            .is_some_and(|r| r.zero_on_box(lo, hi))
        {
            return Some("beyond its bounds' falloff band");
        }
        if self
            .compiled
            .front
            .as_ref()
            .is_some_and(|f| f.zero_on_box(lo, hi, t))
        {
            return Some("ahead of its front's falloff band");
        }
        None
    }

    /// Whether the keys are 0 at `t` (then, at finite points, the
    /// primitive gives exact zeros everywhere).
    #[inline]
    pub fn zero_at(&self, t: f64) -> bool {
        self.keys.as_ref().is_some_and(|k| k.value(t) == 0.0)
    }

    /// Whether the box [lo, hi] lies wholly beyond the bounds' falloff band
    /// or ahead of the front's band at `t` (then the primitive gives exact
    /// zeros on it), whatever the keys.
    #[inline]
    pub fn zero_on_box(&self, lo: &Vector3<f64>, hi: &Vector3<f64>, t: f64) -> bool {
        self.compiled
            .region
            .as_ref()
            .is_some_and(|r| r.zero_on_box(lo, hi))
            || self
                .compiled
                .front
                .as_ref()
                .is_some_and(|f| f.zero_on_box(lo, hi, t))
    }

    /// Whether the primitive has bounds or a front.
    #[inline]
    pub fn is_bounded(&self) -> bool {
        self.bounds.is_some() || self.front.is_some()
    }

    /// Whether [`Primitive::reaches_box`] can ever be false: the primitive
    /// has bounds, a front or keys.
    pub fn is_limited(&self) -> bool {
        self.keys.is_some() || self.bounds.is_some() || self.front.is_some()
    }

    /// Peak |G_i| over space and time, m/s (weights are ≤ 1, so ignored).
    pub fn speed_bound(&self) -> f64 {
        let peak = self.flow.speed_bound();
        let gain = self.keys.as_ref().map_or(1.0, Keyframes::max_abs);
        peak * gain
    }

    /// Checks this primitive; items are named relative to it (`core_radius`).
    pub(super) fn validate(&self) -> Result<(), FieldError> {
        self.flow.validate()?;
        if let Some(b) = &self.bounds {
            b.validate().map_err(|e| e.within("bounds"))?;
        }
        if let Some(f) = &self.front {
            f.validate().map_err(|e| e.within("front"))?;
        }
        if let Some(k) = &self.keys {
            k.validate()?;
        }
        Ok(())
    }
}

/// Precomputed evaluation data (unit axes, constant factors), built once.
#[derive(Clone, Debug, PartialEq)]
struct Compiled {
    flow: FlowEval,
    region: Option<RegionEval>,
    front: Option<FrontEval>,
}

impl Compiled {
    fn flow_only(flow: &Flow) -> Self {
        Self {
            flow: flow.compile(),
            region: None,
            front: None,
        }
    }
}

// ---------------------------------------------------------------------------
// Serde: a flat table per primitive (`kind` plus the keys that kind uses).
// A flat struct is used instead of a tagged enum because `deny_unknown_fields`
// does not combine with `#[serde(flatten)]` for the shared keys (bounds, front,
// keys), and keys that belong to another kind are rejected in the conversion.
// The flow keys are those of `FlowKeys`, in its order.

fn kind_name<'de, D: Deserializer<'de>>(d: D) -> Result<Kind, D::Error> {
    crate::util::named::by_name(d, Kind::NAMES)
}

// Called only when the key is there (the field's default is None).
fn core_name<'de, D: Deserializer<'de>>(d: D) -> Result<Option<VortexCore>, D::Error> {
    crate::util::named::by_name(d, &["lamb_oseen", "rankine"]).map(Some)
}

fn interpolation_name<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Interpolation>, D::Error> {
    crate::util::named::by_name(d, &["linear", "step"]).map(Some)
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PrimitiveSpec {
    #[serde(deserialize_with = "kind_name")]
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
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "core_name"
    )]
    core: Option<VortexCore>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    keys: Option<Vec<(f64, f64)>>,
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "interpolation_name"
    )]
    interpolation: Option<Interpolation>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    bounds: Option<BoundsSpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    front: Option<FrontSpec>,
}

impl PrimitiveSpec {
    fn into_primitive(self) -> Result<Primitive, String> {
        let keys = FlowKeys {
            velocity: self.velocity,
            point: self.point,
            axis: self.axis,
            flux: self.flux,
            circulation: self.circulation,
            core_radius: self.core_radius,
            core: self.core,
        };
        let mut p = Primitive::new(Flow::from_keys(self.kind, &keys)?);
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
            p = p.with_front(f.into_front());
        }
        Ok(p)
    }

    fn from_primitive(p: &Primitive) -> Self {
        let (kind, flow) = p.flow.to_keys();
        PrimitiveSpec {
            kind,
            velocity: flow.velocity,
            point: flow.point,
            axis: flow.axis,
            flux: flow.flux,
            circulation: flow.circulation,
            core_radius: flow.core_radius,
            core: flow.core,
            keys: p.keys.as_ref().map(|k| k.keys.clone()),
            interpolation: p.keys.as_ref().map(|k| k.interpolation),
            bounds: p.bounds.as_ref().map(BoundsSpec::from_bounds),
            front: p.front.as_ref().map(FrontSpec::from_front),
        }
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
