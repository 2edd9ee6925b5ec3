//! Validation names the offending item.

use super::super::{
    Bounds, Flow, Front, Interpolation, Keyframes, LineSink, Primitive, Region, VortexCore,
    WindField,
};
use super::tables::sample_field;
use super::{V3, line_source, point_source, v, vortex};

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
        Primitive::new(Flow::LineSink(LineSink {
            point: p,
            axis,
            flux: 1.0,
            core_radius,
        }))
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
