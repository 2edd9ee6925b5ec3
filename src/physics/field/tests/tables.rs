//! TOML: `[[wind]]` tables parse, round-trip, and reject what does not belong.

use serde::{Deserialize, Serialize};

use super::super::{
    Bounds, Flow, Interpolation, LineVortex, Primitive, Region, VortexCore, WindField,
};
use super::{V3, v, vortex};

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

pub(super) fn sample_field() -> WindField {
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
        Flow::LineVortex(LineVortex { core, .. }) => assert_eq!(*core, VortexCore::LambOseen),
        other => panic!("{other:?}"),
    }
    assert_eq!(
        f.primitives()[6].keys().unwrap().interpolation,
        Interpolation::Linear
    );
    match f.primitives()[1].flow() {
        Flow::LineVortex(LineVortex { axis, .. }) => assert_eq!(*axis, v(0.0, 0.0, 2.0)),
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
