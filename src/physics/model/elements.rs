//! The elements a model is built of: springs, wind-catching triangles and
//! bending hinges (the paper's section 2.1), as plain data.

/// A triangle whose doubled area |N| is below this fraction of its squared
/// longest edge is treated as degenerate (no aerodynamic force, not NaN).
pub const DEGENERATE_TRIANGLE_RATIO: f64 = 1e-9;

/// A spring between two particles with a parallel dashpot (section 2.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spring {
    /// First particle index.
    pub i: usize,
    /// Second particle index.
    pub j: usize,
    /// Length at which the spring exerts no force, m.
    pub rest_length: f64,
    /// Hooke stiffness k, N/m.
    pub stiffness: f64,
    /// Dashpot coefficient c along the spring, N·s/m.
    pub damping: f64,
    /// Strain (l − L)/L beyond which the spring breaks for good; `None` means
    /// unbreakable (the paper's "threshold associated with every spring").
    pub break_strain: Option<f64>,
}

/// A triangular surface element that feels the wind (eq. 8–10).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// The three corner particles.
    pub corners: [usize; 3],
    /// Normal coefficient αⁿ, kg/(m²·s): force per area per normal relative speed.
    pub alpha_n: f64,
    /// Tangential coefficient αᵗ, kg/(m²·s).
    pub alpha_t: f64,
}

/// A bending hinge between two triangles that share the edge `edge`, with
/// apexes `apexes[0]` (first triangle) and `apexes[1]` (second). It resists
/// changes of the fold angle θ (0 when flat) about its rest value, which is
/// what keeps a folded leaf folded; unlike a spring across the fold it is as
/// stiff near flat as anywhere else (docs/design/falling-plates.md, "Folded leaves
/// under the linear law", bending near flat).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hinge {
    /// The shared edge (particles a, b).
    pub edge: [usize; 2],
    /// The two apexes (p on one side, q on the other).
    pub apexes: [usize; 2],
    /// Fold angle at rest, rad.
    pub rest_angle: f64,
    /// Bending stiffness k_b, N·m/rad.
    pub stiffness: f64,
    /// Bending damping c_b, N·m·s/rad.
    pub damping: f64,
}

impl Hinge {
    /// The four particles in the order of the fold angle's gradient:
    /// edge a, edge b, apex p, apex q.
    pub fn particles(&self) -> [usize; 4] {
        [self.edge[0], self.edge[1], self.apexes[0], self.apexes[1]]
    }
}
