//! The export formats by the names the command line takes (`glb`, `pc2`,
//! `usd`), and the error for a name that is none of them.

use crate::formats::usd;
use std::fmt;
use std::str::FromStr;

/// An export file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Binary glTF 2.0 (`.glb`): meshes with normals and UVs, node TRS
    /// animation for the rigid part of every object's motion, a fixed set of
    /// morph targets for the deformation of deforming ones.
    Glb,
    /// PC2 point cache (`.pc2`) with the rest-pose mesh (`.obj`), per object.
    Pc2,
    /// USD (`.usda`, text): an Xform per object with the rigid part of its
    /// motion time-sampled, and a Mesh with its points, normals and UVs.
    Usd,
    /// Alembic (`.abc`, Ogawa): an Xform per object with the rigid part of
    /// its motion as a matrix per frame, and a PolyMesh with its points.
    Abc,
}

/// A name that is no export format's.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum UnknownFormat {
    /// Not a format at all.
    #[error("unknown export format '{0}' (expected glb, pc2, usd, usda or abc)")]
    Unknown(String),
    /// Binary USD, which is made from the text by Pixar's library.
    #[error("{}", usd::USDC_HINT)]
    Usdc,
}

impl FromStr for Format {
    type Err = UnknownFormat;
    fn from_str(s: &str) -> Result<Format, UnknownFormat> {
        match s {
            "glb" => Ok(Format::Glb),
            "pc2" => Ok(Format::Pc2),
            "usd" | "usda" => Ok(Format::Usd),
            "abc" => Ok(Format::Abc),
            "usdc" => Err(UnknownFormat::Usdc),
            _ => Err(UnknownFormat::Unknown(s.to_string())),
        }
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Format::Glb => "glb",
            Format::Pc2 => "pc2",
            Format::Usd => "usd",
            Format::Abc => "abc",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_parses_and_names_unknown_ones() {
        assert_eq!("glb".parse::<Format>(), Ok(Format::Glb));
        assert_eq!("pc2".parse::<Format>(), Ok(Format::Pc2));
        let e = "fbx".parse::<Format>().unwrap_err().to_string();
        assert!(e.contains("fbx") && e.contains("glb, pc2, usd"), "{e}");
        assert_eq!("usd".parse::<Format>(), Ok(Format::Usd));
        assert_eq!("usda".parse::<Format>(), Ok(Format::Usd));
        assert_eq!("abc".parse::<Format>(), Ok(Format::Abc));
        let e = "usdc".parse::<Format>().unwrap_err().to_string();
        assert!(e.contains("usd-core") && e.contains("Export"), "{e}");
    }
}
