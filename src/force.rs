//! Force terms, each a function that adds its contribution into a force
//! accumulator (one entry per particle). The paper's equations are quoted in
//! each doc comment; [`Forces`] sums them in a fixed order so results are
//! reproducible bit for bit.

use crate::model::Model;
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
    for (s, spring) in model.springs.iter().enumerate() {
        if !alive[s] {
            continue;
        }
        let (i, j) = (spring.i, spring.j);
        let d = x[i] - x[j];
        let l2 = d.norm_squared();
        if l2 == 0.0 {
            continue;
        }
        let l = l2.sqrt();
        let n = d / l;
        let stretch_rate = (v[i] - v[j]).dot(&n);
        let f = n * (-spring.stiffness * (l - spring.rest_length) - spring.damping * stretch_rate);
        force[i] += f;
        force[j] -= f;
    }
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
/// `wind` holds G at every particle, or is `None` in still air.
pub fn triangle_aero(model: &Model, x: &[V3], v: &[V3], wind: Option<&[V3]>, force: &mut [V3]) {
    for tri in &model.triangles {
        let [a, b, c] = tri.corners;
        let e1 = x[b] - x[a];
        let e2 = x[c] - x[a];
        let big_n = e1.cross(&e2);
        let n2 = big_n.norm_squared();
        // F → 0 continuously as |N| → 0; only an exactly flat triangle would
        // divide by zero below, so it alone is skipped.
        if n2 <= f64::MIN_POSITIVE {
            continue;
        }
        let doubled_area = n2.sqrt();
        let area = 0.5 * doubled_area;
        // αᵗ A v_r + (αⁿ − αᵗ) A (n·v_r) n, with A n (n·v) = N (N·v) / (2|N|).
        let tangential = tri.alpha_t * area;
        let normal_excess = (tri.alpha_n - tri.alpha_t) / (2.0 * doubled_area);
        for &i in &tri.corners {
            let v_rel = match wind {
                Some(g) => g[i] - v[i],
                None => -v[i],
            };
            force[i] += tangential * v_rel + big_n * (normal_excess * big_n.dot(&v_rel));
        }
    }
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
            ("aero", self.aero.norm()),
            ("drag", self.drag.norm()),
        ];
        terms
            .into_iter()
            .fold(("none", 0.0), |best, t| if t.1 > best.1 { t } else { best })
    }
}

/// Sums all force terms of a model with preallocated scratch space, so that
/// evaluating forces inside the step loop never allocates.
#[derive(Clone, Debug)]
pub struct Forces {
    wind: Vec<V3>,
    scratch: Vec<V3>,
    evaluations: u64,
}

impl Forces {
    /// Scratch space sized for `model`.
    pub fn new(model: &Model) -> Forces {
        Forces {
            wind: vec![V3::zeros(); model.len()],
            scratch: vec![V3::zeros(); model.len()],
            evaluations: 0,
        }
    }

    /// Number of full force evaluations so far (a machine-independent
    /// measure of work).
    pub fn evaluations(&self) -> u64 {
        self.evaluations
    }

    fn sample_wind(&mut self, model: &Model, x: &[V3], t: f64) -> Option<&[V3]> {
        if model.wind.is_still() {
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
        force.fill(V3::zeros());
        gravity(model, force);
        springs(model, x, v, alive, force);
        let wind = self.sample_wind(model, x, t);
        triangle_aero(model, x, v, wind, force);
        particle_drag(model, v, wind, force);
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
            aero: term(&mut |me, s| {
                let wind = me.sample_wind(model, x, t).map(|w| w.to_vec());
                triangle_aero(model, x, v, wind.as_deref(), s)
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
