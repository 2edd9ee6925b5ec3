//! Step 5 of the method ([`super`]): the ordered rules and the thresholds
//! they test, the two of those calibrated on people's labels
//! ([`Calibration`]), and the verdict with its margins and reason.

use serde::{Deserialize, Serialize};

use super::features::PathFeatures;
use crate::motion::class::{MotionClass, Regime};
use crate::motion::rules::{self, Cond, Rule};

/// Largest modulation of a steady descent: the spread of the descent speed
/// about its trend, over its mean, noise removed (our choice: a leaf
/// falling steadily or gliding has none, tumbling and rocking plates 7–100
/// % — the real squares' smallest is 7 %, leafmagic's tumbling cards'
/// 9 %).
pub const STEADY_MAX_MODULATION: f64 = 0.04;

/// Least drift ratio of a glide or a tumble: a path ≥ 5.7° from the
/// vertical (the full classifier's
/// [`crate::motion::classify::GLIDE_MIN_DRIFT_RATIO`]).
pub const GLIDE_MIN_DRIFT: f64 = 0.1;

/// Least Froude number U/√(gL) of a steady fall straight down that is not
/// a floater's: a broadside plate falls slowly (a floater "seemed to float
/// … gently down", Haumann et al. §4.1), a leaf spinning about the vertical
/// or diving edge-on fast. Our choice, from leafmagic's own falls: its
/// steady floaters fall at Fr 0.3–1.9, its spinners that fall straight
/// down at 2.0–9 (docs/guide/classification.md).
pub const STEADY_MAX_FROUDE: f64 = 2.0;

/// Least Froude number of a fall straight down (drift below
/// [`GLIDE_MIN_DRIFT`]) that is a spinner's even when its descent is
/// modulated: twice [`STEADY_MAX_FROUDE`]. Empirical, not clean: on
/// leafmagic's own falls three spinners autorotating with a modulated
/// descent fall at Fr 4.7–5.2, but two lilters at Fr 4.6–4.7 too; the rule
/// gains one fall net on the corpus and three on the held-out falls, which
/// were not looked at when it was chosen (docs/guide/classification.md).
pub const PLUNGE_MIN_FROUDE: f64 = 2.0 * STEADY_MAX_FROUDE;

/// Least straightness |∫v_h dt| / ∫|v_h| dt of a tumble: the path is a
/// straight slanted line (Mahadevan, Ryu & Samuel 1999: "descent along a
/// path at a nearly constant incline"; people labelling the real squares:
/// tumbling paper glides off on a straight slanted line, chaotic paper
/// swings, reverses and wanders). Calibrated on the real squares
/// (docs/guide/classification.md).
pub const TUMBLE_MIN_STRAIGHTNESS: f64 = 0.65;

/// Least area maxima per second of a tumble when area signals are given:
/// two maxima per turn, so a turn rate of at least 11 rad/s. Calibrated on
/// the real squares (docs/guide/classification.md).
pub const TUMBLE_MIN_AREA_MAXIMA_PER_S: f64 = 3.5;

/// Least periodicity of the area signals of a regular tumble, the second
/// way a record with areas is named a tumble: a plate turning steadily
/// about a horizontal axis shows the same area curve turn after turn,
/// chaotic paper does not (the criterion of periodic against chaotic
/// motion of [`FLUTTER_MIN_PERIODICITY`], the same value). This is what
/// names the slow tumbles the rate threshold misses: leafmagic's 5 cm
/// square cards of 100–500 g/m² tumble at 2.7–3.3 maxima/s, under
/// [`TUMBLE_MIN_AREA_MAXIMA_PER_S`], most at a periodicity of 0.8–1.0,
/// while no chaotic real square on a straight path reaches 0.8
/// (docs/guide/classification.md).
pub const TUMBLE_MIN_AREA_PERIODICITY: f64 = FLUTTER_MIN_PERIODICITY;

/// Least area maxima per second of a regular tumble: one turn a second, so
/// that a record of 1–1.5 s holds the turns its periodicity is measured on.
pub const TUMBLE_REGULAR_MIN_AREA_MAXIMA_PER_S: f64 = 2.0;

/// Fewest reversals of the horizontal velocity of a flutter: two periods
/// (the full classifier asks for three,
/// [`crate::motion::classify::MIN_OSCILLATION_PERIODS`], over a window of
/// seconds; a record of 1–1.5 s holds two of a flutter at 1.5 Hz, and the
/// periodicity asked for below tells a regular swing from a chaotic one).
pub const FLUTTER_MIN_REVERSALS: usize = 4;

/// Least spread of a flutter's horizontal speed: it comes to rest at each
/// reversal (the |·| of a sine has a spread of 0.48), where a helix seen
/// along one axis also "reverses" at constant speed (our choice, half of
/// the sine's).
pub const FLUTTER_MIN_SPEED_SPREAD: f64 = 0.25;

/// Least periodicity of a flutter's swing: flutter is periodic, chaos is
/// not (Field et al. 1997). Our choice: leafmagic's and MuJoCo's
/// flutterers swing at 0.9–1.0, its lilters below 0.7.
pub const FLUTTER_MIN_PERIODICITY: f64 = 0.8;

/// Fewest net turns of the horizontal velocity's direction, and its least
/// consistency, of an autorotation: a helix (the full classifier's
/// [`crate::motion::classify::AUTOROTATION_MIN_YAW_TURNS`] and
/// [`crate::motion::classify::AUTOROTATION_MIN_YAW_CONSISTENCY`], on the
/// path instead of the attitude), descending steadily (modulation below
/// [`HELIX_MAX_MODULATION`]: autorotation is a steady state).
pub const HELIX_MIN_TURNS: f64 = 1.0;
/// See [`HELIX_MIN_TURNS`].
pub const HELIX_MIN_CONSISTENCY: f64 = 0.9;
/// Largest radius of an autorotation's helix, chords: a leaf spinning about
/// the vertical drags its centre round a circle of about its own size,
/// while a floater gliding in a turn describes a wide one (our choice:
/// leafmagic's autorotating spinners circle at 0.2–3 chords, most of its
/// turning floaters at 3–7; docs/guide/classification.md).
pub const HELIX_MAX_RADIUS_CHORDS: f64 = 3.0;
/// See [`HELIX_MIN_TURNS`] (our choice: leafmagic's autorotating spinners
/// modulate their descent by at most 9 %, chaotic paper by 13 % and more).
pub const HELIX_MAX_MODULATION: f64 = 0.1;

/// The two thresholds calibrated on people's labels of the real paper
/// squares (docs/guide/classification.md): the rest are physical or taken from
/// the full classifier and are not refitted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calibration {
    /// [`TUMBLE_MIN_STRAIGHTNESS`].
    pub tumble_min_straightness: f64,
    /// [`TUMBLE_MIN_AREA_MAXIMA_PER_S`].
    pub tumble_min_area_maxima_per_s: f64,
}

impl Default for Calibration {
    fn default() -> Self {
        Calibration {
            tumble_min_straightness: TUMBLE_MIN_STRAIGHTNESS,
            tumble_min_area_maxima_per_s: TUMBLE_MIN_AREA_MAXIMA_PER_S,
        }
    }
}

/// Which inputs a classification used.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Inputs {
    /// The orientation (and the path): the full classifier.
    Orientation,
    /// The path and projected-area signals.
    Areas,
    /// The path only.
    Path,
}

impl Inputs {
    /// In words, for reports.
    pub fn describe(self) -> &'static str {
        match self {
            Inputs::Orientation => "orientation and path",
            Inputs::Areas => "path and projected areas (no orientation)",
            Inputs::Path => "path only (no orientation, no areas)",
        }
    }
}

/// What [`classify_path`](super::classify_path) decided.
#[derive(Clone, Debug)]
pub struct PathVerdict {
    /// Floater, spinner, lilter or undetermined.
    pub class: MotionClass,
    /// The finer regime.
    pub regime: Regime,
    /// Why.
    pub reason: String,
    /// Which inputs were used.
    pub inputs: Inputs,
    /// The numbers behind it.
    pub features: PathFeatures,
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum RuleId {
    Helix,
    Flutter,
    Steady,
    Plunge,
    Glide,
    Tumble,
    RegularTumble,
    FastPlunge,
    TurningPlunge,
    Chaotic,
}

/// The ordered rules of the module docs, step 5 (first match wins).
// one piece: a table, read top to bottom in the order the rules are tried
// and the module docs list them; the conditions built before it are those
// several rules share or that depend on the inputs.
fn rules(f: &PathFeatures, inputs: Inputs, cal: &Calibration) -> Vec<Rule<RuleId>> {
    use MotionClass as C;
    let rule = |id, class, regime, conds| Rule {
        id,
        class,
        regime,
        conds,
    };
    // Steady: no modulation above the threshold, or none the noise lets
    // one measure.
    let steady_max = STEADY_MAX_MODULATION.max(f.modulation_noise);
    let steady = || Cond::lt(f.descent_speed_cv, steady_max, STEADY_MAX_MODULATION);
    let vertical = || Cond::lt(f.drift_ratio, GLIDE_MIN_DRIFT, GLIDE_MIN_DRIFT);
    let on_a_slanted_line = || {
        vec![
            Cond::ge(f.straightness, cal.tumble_min_straightness, 0.2),
            Cond::ge(f.drift_ratio, GLIDE_MIN_DRIFT, GLIDE_MIN_DRIFT),
        ]
    };
    let mut tumble = on_a_slanted_line();
    let area_maxima = f.area_maxima_per_s.unwrap_or(0.0);
    if inputs == Inputs::Areas {
        tumble.push(Cond::ge(
            area_maxima,
            cal.tumble_min_area_maxima_per_s,
            0.5 * TUMBLE_MIN_AREA_MAXIMA_PER_S,
        ));
    }
    // A slow tumble: turning regularly, if not fast (areas only; without
    // them the rule above already asks no rate).
    let regular_tumble = if inputs == Inputs::Areas {
        let mut c = on_a_slanted_line();
        c.push(Cond::ge(
            f.area_periodicity.unwrap_or(0.0),
            TUMBLE_MIN_AREA_PERIODICITY,
            0.2,
        ));
        c.push(Cond::ge(
            area_maxima,
            TUMBLE_REGULAR_MIN_AREA_MAXIMA_PER_S,
            0.5 * TUMBLE_REGULAR_MIN_AREA_MAXIMA_PER_S,
        ));
        Some(rule(RuleId::RegularTumble, C::Spinner, Regime::Tumble, c))
    } else {
        None
    };
    // A glide turns no plate: where the record's jitter is too large to
    // tell a steady descent from a modulated one (at video rates it holds
    // a tumble's own modulation, docs/guide/classification.md, "Frame rates"),
    // the areas must not show a plate turning at a tumble's rate either.
    let mut glide = vec![
        steady(),
        Cond::ge(f.drift_ratio, GLIDE_MIN_DRIFT, GLIDE_MIN_DRIFT).regime_only(),
    ];
    if inputs == Inputs::Areas && f.modulation_noise > STEADY_MAX_MODULATION {
        glide.push(Cond::lt(
            area_maxima,
            cal.tumble_min_area_maxima_per_s,
            0.5 * TUMBLE_MIN_AREA_MAXIMA_PER_S,
        ));
    }
    vec![
        rule(
            RuleId::Helix,
            C::Spinner,
            Regime::Autorotation,
            vec![
                Cond::ge(f.path_turns.abs(), HELIX_MIN_TURNS, 1.0),
                Cond::ge(f.path_turn_consistency, HELIX_MIN_CONSISTENCY, 0.1),
                Cond::lt(
                    f.descent_speed_cv,
                    HELIX_MAX_MODULATION,
                    HELIX_MAX_MODULATION,
                ),
                Cond::lt(
                    f.helix_radius_chords,
                    HELIX_MAX_RADIUS_CHORDS,
                    HELIX_MAX_RADIUS_CHORDS,
                ),
            ],
        ),
        rule(
            RuleId::Flutter,
            C::Floater,
            Regime::Flutter,
            vec![
                Cond::ge(
                    f.reversals as f64,
                    FLUTTER_MIN_REVERSALS as f64,
                    FLUTTER_MIN_REVERSALS as f64,
                ),
                Cond::ge(f.swing_periodicity, FLUTTER_MIN_PERIODICITY, 0.2),
                Cond::ge(
                    f.horizontal_speed_spread,
                    FLUTTER_MIN_SPEED_SPREAD,
                    FLUTTER_MIN_SPEED_SPREAD,
                ),
                vertical(),
            ],
        ),
        rule(
            RuleId::Steady,
            C::Floater,
            Regime::Steady,
            vec![
                steady(),
                vertical().regime_only(),
                Cond::lt(f.froude_number, STEADY_MAX_FROUDE, 0.5 * STEADY_MAX_FROUDE),
            ],
        ),
        rule(
            RuleId::Plunge,
            C::Spinner,
            Regime::Autorotation,
            vec![
                steady(),
                vertical(),
                Cond::ge(f.froude_number, STEADY_MAX_FROUDE, 0.5 * STEADY_MAX_FROUDE),
            ],
        ),
        rule(RuleId::Glide, C::Floater, Regime::Glide, glide),
        rule(RuleId::Tumble, C::Spinner, Regime::Tumble, tumble),
    ]
    .into_iter()
    .chain(regular_tumble)
    .chain([
        rule(
            RuleId::FastPlunge,
            C::Spinner,
            Regime::Autorotation,
            vec![
                vertical(),
                Cond::ge(f.froude_number, PLUNGE_MIN_FROUDE, 0.5 * STEADY_MAX_FROUDE),
            ],
        ),
        // Autorotation whose centre circles irregularly: straight down and
        // fast, nearly steady, and turning the same way on the whole
        // (rule 1's turns and modulation without its consistency and
        // radius). Empirical, as rule 7: on the consistency corpus it names
        // one spinner (autorotating at 12 rad/s, its path turning 5 times
        // at consistency 0.67) the rules above left chaotic, and changes
        // no other verdict there or on the real squares; on the held-out
        // falls it changes one, wrong either way (docs/guide/classification.md).
        rule(
            RuleId::TurningPlunge,
            C::Spinner,
            Regime::Autorotation,
            vec![
                vertical(),
                Cond::ge(f.froude_number, STEADY_MAX_FROUDE, 0.5 * STEADY_MAX_FROUDE),
                Cond::lt(
                    f.descent_speed_cv,
                    HELIX_MAX_MODULATION,
                    HELIX_MAX_MODULATION,
                ),
                Cond::ge(f.path_turns.abs(), HELIX_MIN_TURNS, 1.0),
            ],
        ),
        rule(RuleId::Chaotic, C::Lilter, Regime::Chaotic, vec![]),
    ])
    .collect()
}

/// Applies the rules and fills in margins and the reason.
pub(super) fn decide(f: PathFeatures, inputs: Inputs, calibration: &Calibration) -> PathVerdict {
    verdict(f, inputs, calibration)
}

/// The decision for features already measured (what [`classify_path`](super::classify_path)
/// does after measuring): cross-validation refits [`Calibration`] without
/// measuring again. `inputs` says whether the area features count.
pub fn verdict(mut f: PathFeatures, inputs: Inputs, calibration: &Calibration) -> PathVerdict {
    let rules = rules(&f, inputs, calibration);
    let k = rules
        .iter()
        .position(Rule::fires)
        .unwrap_or(rules.len() - 1);
    (f.margin, f.regime_margin) = rules::margins(&rules, k);
    let chosen = &rules[k];
    PathVerdict {
        class: chosen.class,
        regime: chosen.regime,
        reason: reason(chosen.id, &f),
        inputs,
        features: f,
    }
}

/// Human-readable justification quoting the deciding features.
fn reason(id: RuleId, f: &PathFeatures) -> String {
    let areas = match (f.area_maxima_per_s, f.area_turn_rate_rad_s) {
        (Some(m), Some(w)) => format!(", {m:.1} area maxima per second (≈ {w:.0} rad/s)"),
        _ => String::new(),
    };
    let said = match id {
        RuleId::Helix => format!(
            "autorotation: the path is a helix, its horizontal velocity turned {:.1} times the same way (consistency {:.2}), descending steadily at {:.2} m/s",
            f.path_turns.abs(),
            f.path_turn_consistency,
            f.mean_descent_speed_m_s
        ),
        RuleId::Steady => format!(
            "steady descent at {:.2} m/s (Froude number {:.2}, modulation {:.2}), drift ratio {:.2}",
            f.mean_descent_speed_m_s, f.froude_number, f.descent_speed_cv, f.drift_ratio
        ),
        RuleId::FastPlunge => format!(
            "falls straight down fast (Froude number {:.2} ≥ {PLUNGE_MIN_FROUDE}, drift ratio {:.2}), its descent modulated ({:.2}): a leaf spinning about the vertical, not a lilter rocking broadside",
            f.froude_number, f.drift_ratio, f.descent_speed_cv
        ),
        RuleId::TurningPlunge => format!(
            "falls straight down fast (Froude number {:.2}, drift ratio {:.2}), nearly steadily (modulation {:.2}), its path turning {:.1} times on the whole (consistency {:.2}): a leaf spinning about the vertical whose centre circles irregularly",
            f.froude_number,
            f.drift_ratio,
            f.descent_speed_cv,
            f.path_turns.abs(),
            f.path_turn_consistency
        ),
        RuleId::Plunge => format!(
            "falls straight down steadily and fast (Froude number {:.2} ≥ {STEADY_MAX_FROUDE}, modulation {:.2}): a leaf spinning about the vertical; an edge-on dive would look the same without orientation or areas",
            f.froude_number, f.descent_speed_cv
        ),
        RuleId::Glide => format!(
            "glide: steady descent (modulation {:.2}) {:.0}° from the vertical (drift ratio {:.2}, straightness {:.2})",
            f.descent_speed_cv, f.glide_angle_deg, f.drift_ratio, f.straightness
        ),
        RuleId::Tumble => format!(
            "tumble: glides off on a straight line (straightness {:.2}) {:.0}° from the vertical, its descent modulated ({:.2}){areas}",
            f.straightness, f.glide_angle_deg, f.descent_speed_cv
        ),
        RuleId::RegularTumble => format!(
            "tumble: glides off on a straight line (straightness {:.2}) {:.0}° from the vertical, turning regularly (area periodicity {:.2}){areas}",
            f.straightness,
            f.glide_angle_deg,
            f.area_periodicity.unwrap_or(0.0)
        ),
        RuleId::Flutter => format!(
            "flutter: swings regularly from side to side ({} reversals in {:.2} s, periodicity {:.2}) about a vertical path (drift ratio {:.2})",
            f.reversals,
            f.t_end_s - f.t_start_s,
            f.swing_periodicity,
            f.drift_ratio
        ),
        RuleId::Chaotic => format!(
            "chaotic: swings, reverses and wanders (straightness {:.2}, {} reversals, drift ratio {:.2}, modulation {:.2}){areas}",
            f.straightness, f.reversals, f.drift_ratio, f.descent_speed_cv
        ),
    };
    // A steady verdict the record's own resolution decided: its jitter
    // (second differences, which at video rates also hold any motion
    // faster than the frames follow) was larger than the modulation a
    // steady fall may have.
    let steady = matches!(id, RuleId::Steady | RuleId::Plunge | RuleId::Glide);
    if steady && f.modulation_noise > STEADY_MAX_MODULATION {
        format!(
            "{said}; steady only as far as the record resolves: its jitter at {:.1} Hz would hide a modulation up to {:.2}",
            f.sample_rate_hz, f.modulation_noise
        )
    } else {
        said
    }
}
