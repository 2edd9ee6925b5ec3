//! `plate`: writes a flat plate of paper as a leaf file (the falling-plate
//! literature's uniform rigid plate, [`leafmagic::leaf::plates::plate`], or
//! with `--bending-stiffness` a sheet that bends, [`flexible`]).

use super::args::PlateArgs;
use anyhow::{Context, Result, bail};
use leafmagic::leaf::plates::{PlateShape, flexible, plate as build_plate};
use leafmagic::leaf::{AeroLawName, AeroSpec, PAPER_ALPHA};

/// A plate's mass for the report: grams, as paper is weighed, or
/// kilograms in scientific notation from a kilogram up (grams of a huge
/// --areal-density would overflow to "inf").
fn mass_text(kg: f64) -> String {
    if kg < 1.0 {
        format!("{:.3} g", kg * 1e3)
    } else {
        format!("{kg:.3e} kg")
    }
}

/// The library's aspect of the plate asked for: `--aspect` as given, or
/// for a cross its span over its arm width (`--size` / `--arm-width`).
fn plate_aspect(args: &PlateArgs) -> Result<f64> {
    match (args.shape, args.arm_width) {
        (PlateShape::Cross, _) if args.aspect != 1.0 => bail!(
            "--aspect: a cross has none: its arms are --size long (tip to tip) and --arm-width wide"
        ),
        (PlateShape::Cross, None) => {
            bail!("--shape cross needs --arm-width: the width of each arm, metres")
        }
        (PlateShape::Cross, Some(w)) => {
            let span = args.size;
            if !(span.is_finite() && span > 0.0) {
                bail!("--size: must be a finite number > 0 m (a cross's span), got {span}");
            }
            if !(w.is_finite() && w > 0.0 && w < span) {
                bail!(
                    "--arm-width: must be above 0 and below the cross's span (--size {span} m), got {w}"
                );
            }
            Ok(span / w)
        }
        (other, Some(_)) => bail!(
            "--arm-width: only a cross has arms (a {} has none)",
            other.as_str()
        ),
        (_, None) => Ok(args.aspect),
    }
}

/// `plate`: builds the plate, checks it makes a valid model and writes it
/// (to `--out`, atomically, or to standard output).
pub fn plate(args: PlateArgs) -> Result<()> {
    // A `--law paper` plate takes the paper's prototypes' coefficients.
    let aero = match args.law.law() {
        AeroLawName::Linear => AeroSpec::linear(PAPER_ALPHA.0, PAPER_ALPHA.1),
        law => AeroSpec::named(law),
    };
    let aspect = plate_aspect(&args)?;
    let mut spec = build_plate(args.shape, args.size, aspect, args.areal_density, aero)?;
    if let Some(d) = args.bending_stiffness {
        spec = flexible(spec, d)?;
    }
    spec.model()
        .with_context(|| format!("the plate {} is not a valid leaf", spec.name))?;
    let text = spec.to_toml();
    match &args.out {
        Some(path) => {
            leafmagic::util::io::write_atomic(path, text.as_bytes())
                .with_context(|| format!("cannot write {}", path.display()))?;
            let model = spec.model()?;
            eprintln!(
                "wrote {} ({}: {} particles, {} triangles, {}, {} law)",
                path.display(),
                spec.name,
                model.len(),
                model.triangles.len(),
                mass_text(model.total_mass()),
                super::args::law_word(spec.aero.law)
            );
        }
        None => print!("{text}"),
    }
    Ok(())
}
