//! Force terms, each a function that adds its contribution into a force
//! accumulator (one entry per particle). The paper's equations are quoted in
//! each doc comment; [`Forces`] sums them in a fixed order so results are
//! reproducible bit for bit.

use crate::model::{AeroLaw, Hinge, Model};
use crate::terms::Terms;
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// Gravity: F_i = m_i g.
pub fn gravity(model: &Model, force: &mut [V3]) {
    let g = model.gravity;
    for (f, &m) in force.iter_mut().zip(&model.mass) {
        *f += m * g;
    }
}

/// Springs with dashpots (section 2.1, "internal forces ... stretching of the
/// springs"). With d = x_i − x_j, l = |d|, n = d/l, rest length L:
///
/// F_i = −k (l − L) n − c ((v_i − v_j)·n) n,   F_j = −F_i.
///
/// Broken springs (`alive[s] == false`) act no more. A spring squeezed to zero
/// length has no direction and exerts no force (rather than NaN).
pub fn springs(model: &Model, x: &[V3], v: &[V3], alive: &[bool], force: &mut [V3]) {
    for (spring, &alive) in model.springs.iter().zip(alive) {
        if !alive {
            continue;
        }
        let (i, j) = (spring.i, spring.j);
        let d = x[i] - x[j];
        let l2 = d.norm_squared();
        if l2 == 0.0 {
            continue;
        }
        let l = l2.sqrt();
        // One division, not three: n = d / l.
        let n = d * (1.0 / l);
        let stretch_rate = (v[i] - v[j]).dot(&n);
        let f = n * (-spring.stiffness * (l - spring.rest_length) - spring.damping * stretch_rate);
        force[i] += f;
        force[j] -= f;
    }
}

/// The fold angle θ of a hinge and its gradient with respect to the four
/// particles (edge a, edge b, apex p, apex q), in that order.
///
/// With ê the unit edge direction and u, w the parts of x_p − x_a and
/// x_q − x_a perpendicular to it (heights h_p = |u|, h_q = |w|),
/// θ = atan2((û × ŵ)·ê, −û·ŵ), which is 0 for a flat pair and ±π when folded
/// shut. Turning û about ê raises θ and turning ŵ lowers it, so
/// ∇_p θ = (ê × û)/h_p and ∇_q θ = −(ê × ŵ)/h_q; the edge particles take
/// ∇_a θ = −(1 − t_p)∇_p θ − (1 − t_q)∇_q θ and ∇_b θ = −t_p ∇_p θ − t_q ∇_q θ
/// with t the apexes' positions along the edge, which makes the gradient
/// invariant under translation and rotation (no net force or torque).
/// `None` for a degenerate hinge (zero-length edge or an apex on the edge).
pub fn dihedral(x: &[V3], hinge: &Hinge) -> Option<(f64, [V3; 4])> {
    fold_sin_cos(x, hinge).map(|(sin, cos, grad)| (sin.atan2(cos), grad))
}

/// Smallest apex height, relative to the hinge's edge length, used for the
/// fold-angle gradient (see `fold_sin_cos`).
pub const MIN_HINGE_HEIGHT_RATIO: f64 = 0.1;

/// sin θ and cos θ of the fold angle (see [`dihedral`]) and its gradient,
/// without the arctangent: the hot path needs only sin(θ − θ₀). Written with
/// the unnormalised normals N_p = e × (x_p − x_a), N_q = e × (x_q − x_a),
/// since N_p/|N_p| = ê × û and |N_p| = |e| h_p: ∇_p θ = |e| N_p / |N_p|².
// Inlined into the hinge loop: returned by value it costs a 120-byte copy.
#[inline(always)]
fn fold_sin_cos(x: &[V3], hinge: &Hinge) -> Option<(f64, f64, [V3; 4])> {
    let [a, b] = hinge.edge;
    let [p, q] = hinge.apexes;
    let xa = x[a];
    let e = x[b] - xa;
    let (rp, rq) = (x[p] - xa, x[q] - xa);
    let (np, nq) = (e.cross(&rp), e.cross(&rq));
    let (np2, nq2, len2) = (np.norm_squared(), nq.norm_squared(), e.norm_squared());
    if np2 <= f64::MIN_POSITIVE || nq2 <= f64::MIN_POSITIVE {
        return None;
    }
    let len = len2.sqrt();
    let inv_norms = 1.0 / (np2 * nq2).sqrt();
    let sin = np.cross(&nq).dot(&e) * (inv_norms / len);
    let cos = -np.dot(&nq) * inv_norms;
    // |∇_p θ| = 1/h_p grows without bound as a triangle collapses onto the
    // hinge; bound the lever at a tenth of the edge (as ARCSim clamps its
    // bending "height"), so a crumpled leaf gets finite forces.
    let floor = MIN_HINGE_HEIGHT_RATIO * MIN_HINGE_HEIGHT_RATIO * len2 * len2;
    let gp = np * (len / np2.max(floor));
    let gq = nq * (-len / nq2.max(floor));
    let inv_len2 = 1.0 / len2;
    let (tp, tq) = (rp.dot(&e) * inv_len2, rq.dot(&e) * inv_len2);
    let ga = -gp * (1.0 - tp) - gq * (1.0 - tq);
    let gb = -gp * tp - gq * tq;
    Some((sin, cos, [ga, gb, gp, gq]))
}

/// Bending hinges: F_i = −(k_b sin(θ − θ₀) + c_b θ̇) ∇_i θ with
/// θ̇ = Σ ∇_j θ · v_j: the force of the energy k_b (1 − cos(θ − θ₀)), which
/// equals ½ k_b (θ − θ₀)² to fourth order, is smooth at every angle and
/// needs no arctangent; plus a damper on the fold rate.
///
/// `rest` holds (sin θ₀, cos θ₀) of every hinge ([`hinge_rest`]), computed
/// once rather than at every evaluation. A hinge with a torn wing
/// (`torn[h]`; an empty mask tears none, see [`Tears`]) bends no more.
pub fn hinges(
    model: &Model,
    rest: &[(f64, f64)],
    x: &[V3],
    v: &[V3],
    torn: &[bool],
    force: &mut [V3],
) {
    for (h, (hinge, &(rest_sin, rest_cos))) in model.hinges.iter().zip(rest).enumerate() {
        if !torn.is_empty() && torn[h] {
            continue;
        }
        let Some((sin, cos, grad)) = fold_sin_cos(x, hinge) else {
            continue;
        };
        let sin_delta = sin * rest_cos - cos * rest_sin;
        let ids = hinge.particles();
        let rate = fold_rate(&ids, &grad, v);
        let torque = -hinge.stiffness * sin_delta - hinge.damping * rate;
        for (&i, g) in ids.iter().zip(&grad) {
            force[i] += g * torque;
        }
    }
}

/// The spring (if any) joining each pair of particles, in either order.
fn spring_between(model: &Model) -> impl Fn(usize, usize) -> Option<usize> {
    let mut by_pair = std::collections::HashMap::new();
    for (k, s) in model.springs.iter().enumerate() {
        by_pair.insert((s.i.min(s.j), s.i.max(s.j)), k);
    }
    move |i, j| by_pair.get(&(i.min(j), i.max(j))).copied()
}

/// For each triangle, the spring (if any) along each of its three edges.
pub fn edge_springs(model: &Model) -> Vec<[Option<usize>; 3]> {
    let between = spring_between(model);
    model
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.corners;
            [(a, b), (b, c), (c, a)].map(|(i, j)| between(i, j))
        })
        .collect()
}

/// For each hinge, the spring (if any) along each edge of its two wings:
/// the shared edge a–b, then a–p, b–p, a–q, b–q.
pub fn hinge_springs(model: &Model) -> Vec<[Option<usize>; 5]> {
    let between = spring_between(model);
    model
        .hinges
        .iter()
        .map(|h| {
            let ([a, b], [p, q]) = (h.edge, h.apexes);
            [(a, b), (a, p), (b, p), (a, q), (b, q)].map(|(i, j)| between(i, j))
        })
        .collect()
}

/// What broken springs have torn: triangles that are no longer surfaces
/// (an edge spring broke; they feel no air) and hinges with a torn wing (a
/// spring along either wing broke; they bend no more). Both masks are empty
/// until the first spring breaks, and an empty mask tears nothing.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Tears {
    /// `triangles[t]`: triangle t is torn.
    pub triangles: Vec<bool>,
    /// `hinges[h]`: hinge h has a torn wing.
    pub hinges: Vec<bool>,
}

/// The fold rate θ̇ = Σ ∇_j θ · v_j of a hinge over its particles `ids`.
#[inline]
pub fn fold_rate(ids: &[usize; 4], grad: &[V3; 4], v: &[V3]) -> f64 {
    ids.iter().zip(grad).map(|(&i, g)| g.dot(&v[i])).sum()
}

/// (sin θ₀, cos θ₀) of every hinge's rest angle, for [`hinges`].
pub fn hinge_rest(model: &Model) -> Vec<(f64, f64)> {
    model
        .hinges
        .iter()
        .map(|h| h.rest_angle.sin_cos())
        .collect()
}

/// The paper's per-triangle aerodynamics, eq. 6–10, read literally: for each
/// corner particle i of a triangle of area A and unit normal n, the relative
/// velocity v_rᵢ = G(x_i) − v_i (eq. 6) is split into its normal part
/// vⁿ = (v_r·n) n and tangential part vᵗ = v_r − vⁿ (eq. 8), and the corner
/// receives
///
/// Fⁿ = αⁿ A vⁿ,  Fᵗ = αᵗ A vᵗ   (eq. 9, 10).
///
/// Convention: each corner gets the whole triangle area A with its own
/// relative velocity, so a flat leaf of areal density σ falls at
/// σ g / (3 αⁿ); the other reading (A/3 per corner) only rescales α.
/// Written with the unnormalised normal N = e₁ × e₂ (|N| = 2A) so that a
/// triangle squeezed to zero area gets no force instead of NaN.
///
/// `wind` holds G at every particle, or is `None` in still air. A model
/// with [`AeroLaw::Quadratic`] gets that law instead
/// ([`crate::aero::quadratic_forces`]).
pub fn triangle_aero(model: &Model, x: &[V3], v: &[V3], wind: Option<&[V3]>, force: &mut [V3]) {
    triangle_aero_intact(model, x, v, wind, &[], force);
}

/// [`triangle_aero`] on the triangles that are not torn (`torn[t]`; an empty
/// mask tears none). A triangle whose edge spring has broken is no longer a
/// surface: left in, its corners, held by nothing, would be spread by the
/// wind, whose force grows with the area it spreads (a runaway).
pub fn triangle_aero_intact(
    model: &Model,
    x: &[V3],
    v: &[V3],
    wind: Option<&[V3]>,
    torn: &[bool],
    force: &mut [V3],
) {
    if let AeroLaw::Quadratic(law) = &model.aero {
        return crate::aero::quadratic_forces(law, model, x, v, wind, torn, force);
    }
    for (tri, big_n, n2) in surfaces(model, x, torn) {
        let doubled_area = n2.sqrt();
        let area = 0.5 * doubled_area;
        // αᵗ A v_r + (αⁿ − αᵗ) A (n·v_r) n, with A n (n·v) = N (N·v) / (2|N|).
        let tangential = tri.alpha_t * area;
        let normal_excess = (tri.alpha_n - tri.alpha_t) / (2.0 * doubled_area);
        match wind {
            Some(g) => {
                for &i in &tri.corners {
                    let v_rel = g[i] - v[i];
                    force[i] += tangential * v_rel + big_n * (normal_excess * big_n.dot(&v_rel));
                }
            }
            // Still air: v_r = −v, written out so the hot loop has no branch.
            None => {
                for &i in &tri.corners {
                    let v_i = v[i];
                    force[i] -= tangential * v_i + big_n * (normal_excess * big_n.dot(&v_i));
                }
            }
        }
    }
}

/// The triangles that act as surfaces, with their unnormalised normal
/// N = e₁ × e₂ (e₁ = x_b − x_a, e₂ = x_c − x_a) and |N|² = 4A²: those not torn (`torn[t]`; an empty mask tears
/// none) and not exactly flat. Forces built on N go to zero continuously as
/// |N| → 0; only an exactly flat triangle would divide by zero, so it alone
/// is skipped. Shared by both aerodynamic laws.
#[inline]
pub(crate) fn surfaces<'m>(
    model: &'m Model,
    x: &'m [V3],
    torn: &'m [bool],
) -> impl Iterator<Item = (&'m crate::model::Triangle, V3, f64)> + 'm {
    model
        .triangles
        .iter()
        .enumerate()
        .filter(|(t, _)| !torn.get(*t).copied().unwrap_or(false))
        .filter_map(|(_, tri)| {
            let [a, b, c] = tri.corners;
            let big_n = (x[b] - x[a]).cross(&(x[c] - x[a]));
            let n2 = big_n.norm_squared();
            (n2 > f64::MIN_POSITIVE).then_some((tri, big_n, n2))
        })
}

/// Linear drag on particles outside any surface, eq. 7: F_i = α (G_i − v_i).
pub fn particle_drag(model: &Model, v: &[V3], wind: Option<&[V3]>, force: &mut [V3]) {
    for (i, &alpha) in model.particle_drag.iter().enumerate() {
        if alpha == 0.0 {
            continue;
        }
        let v_rel = match wind {
            Some(g) => g[i] - v[i],
            None => -v[i],
        };
        force[i] += alpha * v_rel;
    }
}

/// The force on one particle split by source, for diagnostics and tests.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ForceTerms {
    /// m g.
    pub gravity: V3,
    /// Springs and dashpots.
    pub spring: V3,
    /// Bending hinges.
    pub bending: V3,
    /// Triangle aerodynamics (eq. 9–10).
    pub aero: V3,
    /// Particle drag (eq. 7).
    pub drag: V3,
}

impl ForceTerms {
    /// The name and magnitude of the largest term.
    pub fn dominant(&self) -> (&'static str, f64) {
        let terms = [
            ("gravity", self.gravity.norm()),
            ("spring", self.spring.norm()),
            ("bending", self.bending.norm()),
            ("aero", self.aero.norm()),
            ("drag", self.drag.norm()),
        ];
        terms
            .into_iter()
            .fold(("none", 0.0), |best, t| if t.1 > best.1 { t } else { best })
    }
}

/// Sets `mask[e]` for every element e with a broken spring among
/// `springs[e]`; leaves the mask empty while none is broken (sized at the
/// first tear only, refilled in place afterwards).
fn tear_mask<const N: usize>(mask: &mut Vec<bool>, springs: &[[Option<usize>; N]], alive: &[bool]) {
    if !springs.iter().flatten().flatten().any(|&s| !alive[s]) {
        mask.clear();
        return;
    }
    mask.resize(springs.len(), false);
    for (torn, edges) in mask.iter_mut().zip(springs) {
        *torn = edges.iter().flatten().any(|&s| !alive[s]);
    }
}

/// Sums the force terms of a model that its [`Terms`] keep, with
/// preallocated scratch space, so that evaluating forces inside the step
/// loop never allocates.
#[derive(Clone, Debug)]
pub struct Forces {
    wind: Vec<V3>,
    scratch: Vec<V3>,
    evaluations: u64,
    terms: Terms,
    hinge_rest: Vec<(f64, f64)>,
    /// For each triangle, the springs along its edges (with breaking on).
    edge_springs: Vec<[Option<usize>; 3]>,
    /// For each hinge, the springs along its wings (with breaking on).
    hinge_springs: Vec<[Option<usize>; 5]>,
    /// What broken springs have torn (empty until one breaks).
    torn: Tears,
}

impl Forces {
    /// The terms `model` needs ([`Terms::needed`]), scratch space sized for it.
    pub fn new(model: &Model) -> Forces {
        Forces::with_terms(model, Terms::needed(model))
    }

    /// Evaluates exactly `terms` (a term the model gives nothing to do adds
    /// zeros; a term left out is not evaluated).
    pub fn with_terms(model: &Model, terms: Terms) -> Forces {
        Forces {
            wind: if terms.wind {
                vec![V3::zeros(); model.len()]
            } else {
                Vec::new()
            },
            scratch: vec![V3::zeros(); model.len()],
            evaluations: 0,
            terms,
            hinge_rest: hinge_rest(model),
            edge_springs: if terms.breaking {
                edge_springs(model)
            } else {
                Vec::new()
            },
            hinge_springs: if terms.breaking {
                hinge_springs(model)
            } else {
                Vec::new()
            },
            torn: Tears::default(),
        }
    }

    /// Marks as torn the triangles with a broken edge spring (`alive[s]`
    /// false), which feel no more wind, and the hinges with a broken spring
    /// along a wing, which bend no more. Call after springs break.
    pub fn tear(&mut self, alive: &[bool]) {
        tear_mask(&mut self.torn.triangles, &self.edge_springs, alive);
        tear_mask(&mut self.torn.hinges, &self.hinge_springs, alive);
    }

    /// What is torn (empty masks: nothing).
    pub fn torn(&self) -> &Tears {
        &self.torn
    }

    /// The terms evaluated.
    pub fn terms(&self) -> Terms {
        self.terms
    }

    /// Number of full force evaluations so far (a machine-independent
    /// measure of work).
    pub fn evaluations(&self) -> u64 {
        self.evaluations
    }

    fn sample_wind(&mut self, model: &Model, x: &[V3], t: f64) -> Option<&[V3]> {
        if !self.terms.wind {
            return None;
        }
        for (g, p) in self.wind.iter_mut().zip(x) {
            *g = model.wind.velocity(p, t);
        }
        Some(&self.wind)
    }

    /// Total force on every particle at (x, v, t), written into `force`.
    pub fn total(
        &mut self,
        model: &Model,
        x: &[V3],
        v: &[V3],
        alive: &[bool],
        t: f64,
        force: &mut [V3],
    ) {
        self.evaluations += 1;
        let terms = self.terms;
        // Start from gravity rather than zero: one pass fewer than
        // `fill(0)` followed by `gravity`, same sums in the same order.
        if terms.gravity {
            for (f, &m) in force.iter_mut().zip(&model.mass) {
                *f = m * model.gravity;
            }
        } else {
            force.fill(V3::zeros());
        }
        if terms.springs {
            springs(model, x, v, alive, force);
        }
        if terms.hinges {
            hinges(model, &self.hinge_rest, x, v, &self.torn.hinges, force);
        }
        // Moved out for the call (no allocation): the wind borrows self.
        let torn = std::mem::take(&mut self.torn.triangles);
        let wind = self.sample_wind(model, x, t);
        if terms.aero {
            triangle_aero_intact(model, x, v, wind, &torn, force);
        }
        if terms.particle_drag {
            particle_drag(model, v, wind, force);
        }
        self.torn.triangles = torn;
    }

    /// Acceleration a_i = F_i / m_i (eq. 1); zero for fixed particles.
    pub fn acceleration(
        &mut self,
        model: &Model,
        x: &[V3],
        v: &[V3],
        alive: &[bool],
        t: f64,
        acc: &mut [V3],
    ) {
        self.total(model, x, v, alive, t, acc);
        if self.terms.rigid {
            crate::rigid::accelerations(&model.rigid, x, v, acc);
        }
        for (a, &w) in acc.iter_mut().zip(&model.inv_mass) {
            *a *= w;
        }
    }

    /// Each force term on particle `p` separately.
    pub fn terms_on(
        &mut self,
        model: &Model,
        x: &[V3],
        v: &[V3],
        alive: &[bool],
        t: f64,
        p: usize,
    ) -> ForceTerms {
        let mut scratch = std::mem::take(&mut self.scratch);
        let mut term = |f: &mut dyn FnMut(&mut Forces, &mut [V3])| {
            scratch.fill(V3::zeros());
            f(self, &mut scratch);
            scratch[p]
        };
        let terms = ForceTerms {
            gravity: term(&mut |_, s| gravity(model, s)),
            spring: term(&mut |_, s| springs(model, x, v, alive, s)),
            bending: term(&mut |me, s| hinges(model, &me.hinge_rest, x, v, &me.torn.hinges, s)),
            aero: term(&mut |me, s| {
                let wind = me.sample_wind(model, x, t).map(|w| w.to_vec());
                triangle_aero_intact(model, x, v, wind.as_deref(), &me.torn.triangles, s)
            }),
            drag: term(&mut |me, s| {
                let wind = me.sample_wind(model, x, t).map(|w| w.to_vec());
                particle_drag(model, v, wind.as_deref(), s)
            }),
        };
        self.scratch = scratch;
        terms
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hinge() -> Hinge {
        Hinge {
            edge: [0, 1],
            apexes: [2, 3],
            rest_angle: 0.0,
            stiffness: 1.0,
            damping: 0.0,
        }
    }

    fn points() -> Vec<V3> {
        vec![
            V3::new(0.0, 0.0, 0.0),
            V3::new(0.03, 0.004, -0.002),
            V3::new(0.012, 0.02, 0.003),
            V3::new(0.018, -0.017, 0.006),
        ]
    }

    /// The analytic gradient of the fold angle matches central differences.
    #[test]
    fn dihedral_gradient_matches_finite_differences() {
        let x = points();
        let (theta, grad) = dihedral(&x, &hinge()).unwrap();
        assert!(
            theta.abs() > 0.05,
            "test geometry should be folded, θ = {theta}"
        );
        let eps = 1e-7;
        for p in 0..4 {
            for k in 0..3 {
                let mut plus = x.clone();
                let mut minus = x.clone();
                plus[p][k] += eps;
                minus[p][k] -= eps;
                let fd = (dihedral(&plus, &hinge()).unwrap().0
                    - dihedral(&minus, &hinge()).unwrap().0)
                    / (2.0 * eps);
                assert!(
                    (fd - grad[p][k]).abs() < 1e-5 * grad[p][k].abs().max(1.0),
                    "particle {p} axis {k}: {fd} vs {}",
                    grad[p][k]
                );
            }
        }
    }

    /// Flat is 0; folding both apexes up gives the same sign as folding the
    /// leaf's flaps up; the force has no net force or torque.
    #[test]
    fn hinge_force_is_internal_and_restoring() {
        let mut x = vec![
            V3::new(0.0, 0.0, 0.0),
            V3::new(1.0, 0.0, 0.0),
            V3::new(0.5, 1.0, 0.0),
            V3::new(0.5, -1.0, 0.0),
        ];
        assert!(dihedral(&x, &hinge()).unwrap().0.abs() < 1e-15);
        x[2].z = 0.3;
        x[3].z = 0.3;
        let (theta, _) = dihedral(&x, &hinge()).unwrap();
        assert!(theta.abs() > 0.1);
        let mut parts = crate::model::ModelParts {
            mass: vec![1.0; 4],
            fixed: vec![false; 4],
            rest_position: x.clone(),
            ..Default::default()
        };
        parts.hinges = vec![hinge()];
        let model = Model::new(parts).unwrap();
        let mut f = vec![V3::zeros(); 4];
        hinges(
            &model,
            &hinge_rest(&model),
            &x,
            &[V3::zeros(); 4],
            &[],
            &mut f,
        );
        let net: V3 = f.iter().sum();
        let torque: V3 = x.iter().zip(&f).map(|(p, f)| p.cross(f)).sum();
        assert!(net.norm() < 1e-14 && torque.norm() < 1e-14);
        // Restoring: the force pushes the apexes back towards flat (down).
        assert!(f[2].z < 0.0 && f[3].z < 0.0, "{f:?}");
    }
}
