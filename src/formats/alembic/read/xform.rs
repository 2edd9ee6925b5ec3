//! Alembic transforms: an `AbcGeom_Xform`'s ops and values as a matrix per
//! sample, composed down the object tree into the world matrix that
//! places a mesh's or a point cloud's points.

use super::archive::{Archive, nearest};
use nalgebra::{Matrix4, Rotation3, Unit, Vector3};

type V3 = Vector3<f64>;
type M4 = Matrix4<f64>;

/// An object's transform over time: its local matrix per sample (column
/// vectors), and whether it inherits its parent's.
#[derive(Clone, Debug)]
pub(super) struct Xform {
    pub(super) samples: Vec<(f64, M4)>,
    pub(super) inherits: bool,
}

/// The matrix of Alembic xform ops `ops` (encoded: type in the high
/// nibble) with channel values `vals`, the first op outermost.
pub(super) fn xform_matrix(ops: &[f64], vals: &[f64]) -> Result<M4, String> {
    let mut m = M4::identity();
    let mut at = 0;
    for &op in ops {
        let kind = (op as u32) >> 4;
        let width = match kind {
            0 | 1 => 3,
            2 => 4,
            3 => 16,
            4..=6 => 1,
            _ => return Err(format!("an xform op of unknown type {kind}")),
        };
        let v = vals
            .get(at..at + width)
            .ok_or("an xform's ops need more values than it holds")?;
        at += width;
        let axis = |x: f64, y: f64, z: f64, deg: f64| {
            Rotation3::from_axis_angle(&Unit::new_normalize(V3::new(x, y, z)), deg.to_radians())
                .to_homogeneous()
        };
        let op_m = match kind {
            0 => M4::new_nonuniform_scaling(&V3::new(v[0], v[1], v[2])),
            1 => M4::new_translation(&V3::new(v[0], v[1], v[2])),
            2 if V3::new(v[0], v[1], v[2]).norm() > 0.0 => axis(v[0], v[1], v[2], v[3]),
            2 => M4::identity(),
            // Rows of Imath's row-vector matrix: its transpose acts on columns.
            3 => M4::from_row_slice(v).transpose(),
            4 => axis(1.0, 0.0, 0.0, v[0]),
            5 => axis(0.0, 1.0, 0.0, v[0]),
            _ => axis(0.0, 0.0, 1.0, v[0]),
        };
        m *= op_m;
    }
    Ok(m)
}

/// An Xform's `.xform` compound at `pos`.
pub(super) fn read_xform(a: &Archive<'_>, pos: u64) -> Result<Xform, String> {
    let props = a.compound(pos)?;
    let find = |n: &str| props.iter().find(|p| p.header.name == n);
    let inherits = match find(".inherits") {
        Some(p) => a.sample(p, 0)?.0.first().is_none_or(|&b| b != 0.0),
        None => true,
    };
    let ops = match find(".ops") {
        Some(p) => a.sample(p, 0)?.0,
        None => Vec::new(),
    };
    let samples = match find(".vals") {
        Some(p) => a
            .samples(p)?
            .into_iter()
            .map(|(t, v)| xform_matrix(&ops, &v).map(|m| (t, m)))
            .collect::<Result<_, _>>()?,
        None => vec![(0.0, xform_matrix(&ops, &[])?)],
    };
    Ok(Xform { samples, inherits })
}

/// The world matrix of the transforms `xforms` (the root first) at `t`.
pub(super) fn world_matrix(xforms: &[Xform], t: f64) -> M4 {
    let mut world = M4::identity();
    for x in xforms {
        let local = *nearest(&x.samples, t);
        world = if x.inherits { world * local } else { local };
    }
    world
}

/// A point `c` (x, y, z in the file) placed by `world`, turned from
/// Alembic's y up to z up.
pub(super) fn placed(world: &M4, c: &[f64]) -> V3 {
    let p = world
        .transform_point(&V3::new(c[0], c[1], c[2]).into())
        .coords;
    V3::new(p.x, -p.z, p.y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xform_ops_compose_with_the_first_outermost() {
        let p = |m: &M4, x: V3| m.transform_point(&x.into()).coords;
        // translate (1, 2, 3), then rotate 90° about z: the rotation acts
        // first on the point.
        let m = xform_matrix(&[16.0, 96.0], &[1.0, 2.0, 3.0, 90.0]).unwrap();
        assert!((p(&m, V3::x()) - V3::new(1.0, 3.0, 3.0)).norm() < 1e-12);
        // A matrix op is Imath's row-vector matrix: its translation is
        // its last row.
        let mut rows = [0.0; 16];
        for k in 0..4 {
            rows[5 * k] = 1.0;
        }
        rows[12..15].copy_from_slice(&[5.0, 6.0, 7.0]);
        let m = xform_matrix(&[48.0], &rows).unwrap();
        assert_eq!(p(&m, V3::zeros()), V3::new(5.0, 6.0, 7.0));
        // Scale, and a rotation about an axis in degrees.
        let m = xform_matrix(&[0.0, 32.0], &[2.0, 3.0, 4.0, 0.0, 0.0, 1.0, 90.0]).unwrap();
        assert!((p(&m, V3::x()) - V3::new(0.0, 3.0, 0.0)).norm() < 1e-12);
        let err = xform_matrix(&[16.0], &[1.0]).unwrap_err();
        assert!(err.contains("more values than it holds"), "{err}");
        assert!(xform_matrix(&[112.0], &[1.0]).is_err());
    }
}
