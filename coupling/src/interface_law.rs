//! The laws of a non-conforming interface point (issue 25, item 2): the traction that the
//! soil exerts on the structure as a function of the gap, and its derivative.
//!
//! The gap `g` (m, a 2D vector) is the soil's displacement at the point less the structure's,
//! plus the part carried from the last step ([`crate::interface_points`]: `g = g_n + Δg`,
//! `Δg = Σ_I N_I Δu_I − Σ_a φ_a Δu_a`). `n` is the structure facet's outward unit normal and
//! `τ = (−n_y, n_x)` its tangent, both taken at the start of the step; `g_N = g · n`,
//! `g_T = g · τ`. Each law gives the traction `T(g)` on the structure (the soil's force per
//! unit reference area), its tangent `C = ∂T/∂g` and the gap to carry into the next step.
//!
//! - **Tie** (bilateral, no slip): `T = β g`, `C = β I`, carried `g`.
//! - **Contact** (unilateral, penalty regularisation; Wriggers 2006, *Computational Contact
//!   Mechanics*, 2nd ed., Springer, doi:10.1007/978-3-540-32609-0, §5.2 and §10.3.1; Laursen
//!   2002, *Computational Contact and Impact Mechanics*, Springer,
//!   doi:10.1007/978-3-662-04864-1, §5.3):
//!   - *open* `g_N ≥ 0` (the soil has pulled away, or touches without pressing): `T = 0`,
//!     `C = 0`, the carried gap reset to zero (the point releases);
//!   - *closed* `g_N < 0`: the contact pressure `t_N = −β_N g_N > 0`, and the normal traction
//!     on the structure `−t_N n` (it pushes the structure inwards);
//!   - the tangential part by a return mapping from the committed state: the carried gap's
//!     tangential part is the elastic tangential gap `g_T,n^e = t_T,n / β_T`, so that the trial
//!     traction is `t_T^tr = β_T g_T = t_T,n + β_T Δg_T`; **stick** where `|t_T^tr| ≤ μ t_N`
//!     (`t_T = t_T^tr`, `∂t_T/∂g_T = β_T`), **slip** otherwise (`t_T = μ t_N s`,
//!     `s = sign t_T^tr`, `∂t_T/∂g_N = −μ β_N s`: the unsymmetric term of `∂t_N`), carrying
//!     `g_T^e = t_T / β_T`. μ = 0 is frictionless (`t_T = 0`, the point slides).
//!
//!   The traction on the structure is `T = −t_N n + t_T τ`; in the frame `(n, τ)`
//!
//!   ```text
//!   stick: C = β_N n⊗n + β_T τ⊗τ,     slip: C = β_N n⊗n − μ β_N s τ⊗n.
//!   ```
//!
//!   The trial is formed from the committed state of the step's start and the gap of the
//!   iterate, never from the last Newton iterate, so a converged step does not depend on the
//!   Newton path (Wriggers 2006, §5.2.2: the slip is integrated by a backward Euler step).

/// State of an interface point in its last evaluation; the numbers are those of the point
/// cloud's `state` field.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum PointState {
    /// No soil in reach, or the soil does not press (contact): no force.
    #[default]
    Open,
    /// Tied, or in contact and sticking.
    Stick,
    /// In contact and sliding (every closed point of a frictionless contact).
    Slip,
}

impl PointState {
    /// `0` open, `1` stick, `2` slip.
    pub fn code(self) -> f64 {
        match self {
            PointState::Open => 0.0,
            PointState::Stick => 1.0,
            PointState::Slip => 2.0,
        }
    }
}

/// The law of a non-conforming interface (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum InterfaceLaw {
    /// Bilateral tie with penalty `β` (Pa/m).
    Tie {
        /// β (Pa/m).
        penalty: f64,
    },
    /// Unilateral contact with Coulomb friction.
    Contact {
        /// β_N (Pa/m), the normal penalty.
        normal_penalty: f64,
        /// β_T (Pa/m), the tangential (stick) penalty.
        tangential_penalty: f64,
        /// Coulomb coefficient μ ≥ 0 (0: frictionless).
        friction: f64,
    },
}

/// What a law gives at one gap.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LawResponse {
    /// Traction on the structure `T` (Pa), global components.
    pub traction: [f64; 2],
    /// `C = ∂T/∂g` (Pa/m), row-major: `tangent[i][j] = ∂T_i/∂g_j`.
    pub tangent: [[f64; 2]; 2],
    /// The gap to carry into the next step if this one converges here.
    pub carried: [f64; 2],
    /// Stored energy per unit area (J/m²): `½ β |g|²` (tie), `½ β_N g_N² + ½ t_T²/β_T`
    /// (contact; the slip's dissipation is not stored).
    pub energy: f64,
    /// Open, stick or slip.
    pub state: PointState,
}

impl InterfaceLaw {
    /// The response at gap `g` (m) of a point whose facet has the outward unit normal `n`,
    /// with the contact pressure's augmented-Lagrangian multiplier `λ_N ≥ 0` (Pa; 0: pure
    /// penalty; ignored by a tie): `t_N = λ_N − β_N g_N` where positive (closed), else open
    /// (Laursen 2002, §6.4; Wriggers 2006, §6.3.3).
    pub fn response(&self, g: [f64; 2], n: [f64; 2], multiplier: f64) -> LawResponse {
        match *self {
            InterfaceLaw::Tie { penalty } => LawResponse {
                traction: g.map(|gk| penalty * gk),
                tangent: [[penalty, 0.0], [0.0, penalty]],
                carried: g,
                energy: 0.5 * penalty * (g[0] * g[0] + g[1] * g[1]),
                state: PointState::Stick,
            },
            InterfaceLaw::Contact { normal_penalty, tangential_penalty, friction } => {
                let tau = [-n[1], n[0]];
                let (gn, gt) = (dot(g, n), dot(g, tau));
                let pressure = multiplier - normal_penalty * gn;
                if pressure <= 0.0 {
                    return LawResponse {
                        traction: [0.0; 2],
                        tangent: [[0.0; 2]; 2],
                        carried: [0.0; 2],
                        energy: 0.0,
                        state: PointState::Open,
                    };
                }
                let trial = tangential_penalty * gt;
                let limit = friction * pressure;
                // (t_T, ∂t_T/∂g_N, ∂t_T/∂g_T, state)
                let (tt, dtt_dgn, dtt_dgt, state) = if trial.abs() <= limit {
                    (trial, 0.0, tangential_penalty, PointState::Stick)
                } else {
                    let s = trial.signum();
                    (limit * s, -friction * normal_penalty * s, 0.0, PointState::Slip)
                };
                // T = −t_N n + t_T τ
                let traction = std::array::from_fn(|i| -pressure * n[i] + tt * tau[i]);
                let tangent = std::array::from_fn(|i| {
                    std::array::from_fn(|j| normal_penalty * n[i] * n[j] + tau[i] * (dtt_dgn * n[j] + dtt_dgt * tau[j]))
                });
                let elastic_gt = if tangential_penalty > 0.0 { tt / tangential_penalty } else { 0.0 };
                LawResponse {
                    traction,
                    tangent,
                    carried: std::array::from_fn(|i| gn * n[i] + elastic_gt * tau[i]),
                    energy: 0.5 * normal_penalty * gn * gn + 0.5 * tt * elastic_gt,
                    state,
                }
            }
        }
    }

    /// The penalty that scales the interface's equations: β (tie) or β_N (contact).
    pub fn penalty(&self) -> f64 {
        match *self {
            InterfaceLaw::Tie { penalty } => penalty,
            InterfaceLaw::Contact { normal_penalty, .. } => normal_penalty,
        }
    }

    /// Whether the law is a contact (unilateral).
    pub fn is_contact(&self) -> bool {
        matches!(self, InterfaceLaw::Contact { .. })
    }
}

impl std::fmt::Display for InterfaceLaw {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            InterfaceLaw::Tie { penalty } => write!(f, "non-conforming tie, penalty {penalty:.6e} Pa/m"),
            InterfaceLaw::Contact { normal_penalty, friction: 0.0, .. } => {
                write!(f, "frictionless contact, penalty {normal_penalty:.6e} Pa/m")
            }
            InterfaceLaw::Contact { normal_penalty, tangential_penalty, friction } => write!(
                f,
                "Coulomb contact, friction {friction}, penalty {normal_penalty:.6e} Pa/m, tangential penalty {tangential_penalty:.6e} Pa/m"
            ),
        }
    }
}

fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

#[cfg(test)]
mod tests {
    use super::*;

    const CONTACT: InterfaceLaw =
        InterfaceLaw::Contact { normal_penalty: 3.0e9, tangential_penalty: 1.0e9, friction: 0.3 };

    /// A normal 25° from the axes, and a gap of normal part `gn` and tangential part `gt`.
    fn frame_and_gap(gn: f64, gt: f64) -> ([f64; 2], [f64; 2]) {
        let a = 25f64.to_radians();
        let n = [a.cos(), a.sin()];
        (n, [gn * n[0] - gt * n[1], gn * n[1] + gt * n[0]])
    }

    /// `C` against central differences of `T` in every state, open, stick and slip (both
    /// directions), without and with an augmented-Lagrangian multiplier (λ_N = 1.5e4 Pa: a
    /// point closed at a small positive gap), relative error < 1e-8; the slip's `C` is
    /// unsymmetric.
    #[test]
    fn tangent_matches_central_differences_in_every_state() {
        for (gn, gt, lambda, state) in [
            (2e-6, 1e-6, 0.0, PointState::Open),
            (-1e-5, 2e-6, 0.0, PointState::Stick),
            (-1e-5, 2e-5, 0.0, PointState::Slip),
            (-1e-5, -2e-5, 0.0, PointState::Slip),
            (1e-6, 1e-6, 1.5e4, PointState::Stick),
            (2e-6, 2e-5, 1.5e4, PointState::Slip),
            (6e-6, 1e-6, 1.5e4, PointState::Open),
        ] {
            let (n, g) = frame_and_gap(gn, gt);
            let r = CONTACT.response(g, n, lambda);
            assert_eq!(r.state, state, "gap ({gn}, {gt})");
            let h = 1e-11;
            let mut worst = 0.0f64;
            for j in 0..2 {
                let (mut p, mut m) = (g, g);
                p[j] += h;
                m[j] -= h;
                let (tp, tm) = (CONTACT.response(p, n, lambda).traction, CONTACT.response(m, n, lambda).traction);
                for i in 0..2 {
                    worst = worst.max(((tp[i] - tm[i]) / (2.0 * h) - r.tangent[i][j]).abs() / 3.0e9);
                }
            }
            println!("{state:?}, λ_N = {lambda}: ∂T/∂g vs central differences, relative error {worst:.1e}");
            assert!(worst < 1e-8, "{state:?}: {worst:.2e}");
            if state == PointState::Slip {
                assert!((r.tangent[0][1] - r.tangent[1][0]).abs() > 1e6, "slip is unsymmetric");
            }
        }
    }

    /// Stick below the cone, slip on it: `|t_T| = μ t_N` while sliding, in the direction of
    /// the trial; the carried tangential gap is the elastic one `t_T/β_T` (the slip is not
    /// carried); a tie is `β g` and carries `g`; frictionless contact has no tangential
    /// traction; an open point carries nothing.
    #[test]
    fn tractions_follow_the_laws() {
        let (n, g) = frame_and_gap(-1e-5, 2e-5);
        let r = CONTACT.response(g, n, 0.0);
        let tau = [-n[1], n[0]];
        let (tn, tt) = (dot(r.traction, n), dot(r.traction, tau));
        println!("slip: t_N = {:.1} Pa (β_N g_N = −3e4), t_T = {tt:.1} Pa (μ t_N = 9e3)", -tn);
        assert!((tn + 3.0e4).abs() < 1e-9 && (tt - 0.3 * 3.0e4).abs() < 1e-9);
        assert!((dot(r.carried, tau) - 9.0e3 / 1.0e9).abs() < 1e-18 && (dot(r.carried, n) + 1e-5).abs() < 1e-18);
        let (_, g) = frame_and_gap(-1e-5, 2e-6);
        let stick = CONTACT.response(g, n, 0.0);
        assert!((dot(stick.traction, tau) - 2.0e3).abs() < 1e-9);
        assert!((0..2).all(|k| (stick.carried[k] - g[k]).abs() < 1e-20), "stick carries the gap");
        let frictionless = InterfaceLaw::Contact { normal_penalty: 3.0e9, tangential_penalty: 3.0e9, friction: 0.0 };
        let r = frictionless.response(g, n, 0.0);
        assert!(dot(r.traction, tau).abs() < 1e-9 && r.state == PointState::Slip && dot(r.carried, tau).abs() < 1e-20);
        let (_, open) = frame_and_gap(1e-6, 5e-6);
        let r = CONTACT.response(open, n, 0.0);
        assert!(r.traction == [0.0; 2] && r.carried == [0.0; 2]);
        let tie = InterfaceLaw::Tie { penalty: 2.0 }.response([1.0, -3.0], n, 0.0);
        assert!(tie.traction == [2.0, -6.0] && tie.carried == [1.0, -3.0]);
    }
}
