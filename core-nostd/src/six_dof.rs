//! Six-DOF bushings: six 1D laws between two rigid nodes, with the
//! "attached" or the "invariant" (mid-rotation) connectivity of Merel,
//! Wander, Masarati and Morandini (Multibody Dynamics 2007, "seed 002").
//!
//! A bushing joins node 1 and node 2, each given by its [`Pose`]: a
//! position and a unit quaternion that turns node-frame vectors into
//! global ones. It is attached at a point fixed in each node frame (the
//! offsets f̄₁, f̄₂), so with d_i = R_i f̄_i and p_i = x_i + d_i the
//! bushing's elongation is d = p₂ - p₁. The relative rotation is
//! R = R₁ᵀR₂ and its rotation vector θ = ax(log R) (seed 002, "relative
//! orientation vector"), whose components are the same in the frames of
//! node 1, node 2 and the mid frame below (Rθ = θ).
//!
//! Each of the six directions has its own 1D law from the catalogue (a
//! [`Bushing`]: backbone plus effects, one per axis, so the bushing may be
//! anisotropic): translations x, y, z take the components of d in the
//! bushing frame and give the force F̄; rotations x, y, z take the
//! components of θ and give the moment M̄. F = R_b F̄ and M = R_b M̄ are the
//! loads in the global frame. Node 1 receives (F, M₁) and node 2 (-F, M₂),
//! the moments including the arms of the attachment points.
//!
//! - **Attached** (seed 002, "attached" angular spring): the bushing frame
//!   is node 1's, R_b = R₁, and the force acts at p₂, so node 1 carries
//!   the whole arm: M₁ = (p₂ - x₁) × F + M, M₂ = -d₂ × F - M. The law is
//!   referred to node 1: with anisotropic laws, swapping the nodes changes
//!   the loads (the seed's car suspension oscillated unstably until the
//!   node order was reversed).
//! - **Invariant** (seed 002, "invariant" mid-rotation): the bushing frame
//!   is the mid frame R̂ = R₁R̃ = R₂R̃ᵀ with R̃ = exp(½θ×), which does not
//!   change when the nodes are swapped. The moment of F about the mid point
//!   is shared with Ĩ = R̂(I + R̃)⁻¹R̂ᵀ = ½(I - (R₁t)×), t = tan(|θ|/4) θ/|θ|
//!   (Ĩ + Ĩᵀ = I, half each at θ = 0): M₁ = d₁ × F + Ĩ(d × F) + M,
//!   M₂ = -d₂ × F + Ĩᵀ(d × F) - M. Swapping the nodes gives the same loads
//!   on each physical node, for laws that are odd in their input (a linear
//!   or symmetric law: every law of the catalogue with an odd backbone);
//!   `tests` checks this to 1e-12 in f64.
//!
//! Both forms balance exactly: ΣF = 0 and Σ(x_i × F_i + M_i) = 0.
//!
//! The seed gives the formulas for the angular spring only; the mapping of
//! the translational part and the moment arms follow the same mid-frame
//! construction (the force is the law's in the mid frame, its moment about
//! the mid point split by Ĩ).
//!
//! **States**: the six axes' [`BushingState`]s, the last loads and the
//! fault flags of the kinematics. A configuration that is not usable (a
//! non-finite position or one beyond a quarter of the guard, an
//! orientation that is not a unit quaternion within 1e-3) is refused as a
//! 1D law refuses an input: the axes keep their states, the last loads are
//! returned and a flag is raised ([`SixDof::step`]).
//!
//! **Stability**: that of each axis law; the kinematics adds none. The
//! rotation vector is the principal one, |θ| ≤ π: at a relative rotation of
//! half a turn the mid frame jumps by a half turn (a bushing never gets
//! there).
//!
//! **Tangent**: [`SixDof::tangent`] gives the consistent 12×12 tangent of
//! the node loads for an implicit solver, from the axes' algorithmic
//! tangents dF̄_k/dx_k ([`SixDofOutput::tangent`]) and the geometric terms
//! (the turning frame, the arms, the moving mid point). It matches central
//! differences of [`SixDof::trial`] to 2e-10 of its largest entry after a
//! loaded history, at rotations of a radian and of a few hundredths.
//!
//! **Cost**: six 1D steps plus the kinematics: three quaternion products
//! (two in the attached form), one quaternion made a matrix for the four
//! rotations into and out of the bushing frame (three attached), two
//! quaternion rotations, four cross products (two attached), one `atan2`
//! and two `rsqrt` (one attached; Newton steps, no division and no libm
//! square root; |v|² below the smallest normal number takes θ = 2v), and
//! the checks of the configuration: two unit quaternions, two positions
//! and six local strains. One engine mount (six axes of a polynomial, 2
//! Maxwell and 3 Jenkins cells) costs 1 553 guest instructions per step on
//! a Cortex-M4F attached and 1 658 invariant, net of the call, on its
//! worst input, band-limited noise (`docs/accuracy-cost.md`, family
//! `six-dof`). The tangent is formed on request, not in the step.

use crate::backbone::Backbone;
use crate::bushing::{Bushing, BushingState, Effect};
use crate::error::{Faults, Param, ParamError, in_range};
use crate::real::{Real, all_within, min_positive, rsqrt};

/// A vector of three components.
pub type Vec3<T> = [T; 3];

/// A 3×3 matrix, by rows.
pub type Mat3<T> = [Vec3<T>; 3];

/// A unit quaternion w + v (Hamilton's convention): the active rotation
/// that turns vectors of a node frame into the global frame.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Quat<T> {
    /// Scalar part, cos(φ/2).
    pub w: T,
    /// Vector part, sin(φ/2) times the axis.
    pub v: Vec3<T>,
}

fn add<T: Real>(a: Vec3<T>, b: Vec3<T>) -> Vec3<T> {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn sub<T: Real>(a: Vec3<T>, b: Vec3<T>) -> Vec3<T> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn scale<T: Real>(a: Vec3<T>, k: T) -> Vec3<T> {
    [a[0] * k, a[1] * k, a[2] * k]
}

fn neg<T: Real>(a: Vec3<T>) -> Vec3<T> {
    [-a[0], -a[1], -a[2]]
}

fn dot<T: Real>(a: Vec3<T>, b: Vec3<T>) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross<T: Real>(a: Vec3<T>, b: Vec3<T>) -> Vec3<T> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// M u.
fn mul_vec<T: Real>(m: &Mat3<T>, u: Vec3<T>) -> Vec3<T> {
    [dot(m[0], u), dot(m[1], u), dot(m[2], u)]
}

/// Mᵀ u.
fn mul_t_vec<T: Real>(m: &Mat3<T>, u: Vec3<T>) -> Vec3<T> {
    add(add(scale(m[0], u[0]), scale(m[1], u[1])), scale(m[2], u[2]))
}

impl<T: Real> Quat<T> {
    /// No rotation.
    pub fn identity() -> Self {
        Self {
            w: T::ONE,
            v: [T::ZERO; 3],
        }
    }

    /// The rotation of angle |r| about r/|r| (a rotation vector, rad),
    /// computed in f64 (construction, scenes and tests).
    pub fn from_rotation_vector(r: [f64; 3]) -> Self {
        let angle = libm::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        // sin(φ/2)/φ, 1/2 at φ = 0.
        let k = if angle > 0.0 {
            libm::sin(0.5 * angle) / angle
        } else {
            0.5
        };
        Self {
            w: T::from_f64(libm::cos(0.5 * angle)),
            v: [
                T::from_f64(k * r[0]),
                T::from_f64(k * r[1]),
                T::from_f64(k * r[2]),
            ],
        }
    }

    /// `self* ⊗ other`: the rotation from `self` to `other`, in the frame
    /// of `self`.
    pub fn conj_mul(self, other: Self) -> Self {
        Self {
            w: self.w * other.w + dot(self.v, other.v),
            v: sub(
                sub(scale(other.v, self.w), scale(self.v, other.w)),
                cross(self.v, other.v),
            ),
        }
    }

    /// The conjugate: the inverse rotation.
    pub fn conj(self) -> Self {
        Self {
            w: self.w,
            v: neg(self.v),
        }
    }

    /// R u: a node-frame vector in the global frame.
    pub fn rotate(self, u: Vec3<T>) -> Vec3<T> {
        // u + 2w (v × u) + 2 v × (v × u)
        let t = cross(self.v, u);
        let t = add(t, t);
        add(add(u, scale(t, self.w)), cross(self.v, t))
    }

    /// Rᵀ u: a global vector in the node frame.
    pub fn rotate_back(self, u: Vec3<T>) -> Vec3<T> {
        self.conj().rotate(u)
    }

    /// R as a matrix: the linear map of [`Quat::rotate`],
    /// (1 - 2|v|²) I + 2 v vᵀ + 2 w \[v\]×, formed with 24 operations, so
    /// that each rotation by it takes 15 against the 30 of `rotate`.
    pub fn matrix(self) -> Mat3<T> {
        let ([x, y, z], w) = (self.v, self.w);
        let (x2, y2, z2) = (x + x, y + y, z + z);
        let (xx, yy, zz) = (x * x2, y * y2, z * z2);
        let (xy, xz, yz) = (x * y2, x * z2, y * z2);
        let (wx, wy, wz) = (w * x2, w * y2, w * z2);
        [
            [T::ONE - (yy + zz), xy - wz, xz + wy],
            [xy + wz, T::ONE - (xx + zz), yz - wx],
            [xz - wy, yz + wx, T::ONE - (xx + yy)],
        ]
    }
}

/// The Hamilton product `self ⊗ other`: `other` first, then `self`.
impl<T: Real> core::ops::Mul for Quat<T> {
    type Output = Self;

    fn mul(self, other: Self) -> Self {
        Self {
            w: self.w * other.w - dot(self.v, other.v),
            v: add(
                add(scale(other.v, self.w), scale(self.v, other.w)),
                cross(self.v, other.v),
            ),
        }
    }
}

/// Position and orientation of a rigid node.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Pose<T> {
    /// Position in the global frame, mm.
    pub position: Vec3<T>,
    /// Orientation: node frame to global frame, a unit quaternion (the
    /// kinematics do not renormalise it).
    pub orientation: Quat<T>,
}

/// How the bushing frame is chosen (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Connectivity {
    /// The frame of node 1; the loads depend on the node order.
    Attached,
    /// The mid frame between the nodes; the node order does not matter.
    Invariant,
}

/// Loads on the two nodes, in the global frame.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Loads<T> {
    /// Force on node 1 and on node 2, N.
    pub force: [Vec3<T>; 2],
    /// Moment on node 1 and on node 2, about each node's position, N·mm.
    pub moment: [Vec3<T>; 2],
}

/// The result of one 6-DOF step.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SixDofOutput<T> {
    /// Loads on the nodes.
    pub loads: Loads<T>,
    /// The six local strains: d in the bushing frame (mm), then θ (rad).
    pub strain: [T; 6],
    /// The six local loads: F̄ (N), then M̄ (N·mm), in the bushing frame.
    pub local: [T; 6],
    /// The six axes' algorithmic tangents dF̄_k/dx_k (bushing frame):
    /// N/mm for the translations, N·mm/rad for the rotations.
    pub tangent: [T; 6],
    /// The bushing frame: node 1's (attached) or the mid frame.
    pub frame: Quat<T>,
    /// Energy dissipated in the step, all axes, mJ.
    pub dissipated: T,
}

/// Running state: the six axes', the last loads and the fault flags of
/// the kinematics.
#[derive(Debug, Clone, PartialEq)]
pub struct SixDofState<T, S> {
    axes: [BushingState<T, S>; 6],
    loads: Loads<T>,
    faults: Faults,
}

impl<T: Real, S> SixDofState<T, S> {
    /// The state of axis `k` (0-2 translations, 3-5 rotations).
    pub fn axis(&self, k: usize) -> Option<&BushingState<T, S>> {
        self.axes.get(k)
    }

    /// The loads after the last accepted step.
    pub fn loads(&self) -> Loads<T> {
        self.loads
    }

    /// Fault flags of the configurations refused since the last
    /// [`SixDofState::clear_faults`] (each axis keeps its own as well).
    pub fn faults(&self) -> Faults {
        self.faults
    }

    /// Clears the flags of the kinematics and of every axis.
    pub fn clear_faults(&mut self) {
        self.faults = Faults::NONE;
        for a in &mut self.axes {
            a.clear_faults();
        }
    }
}

/// The kinematics of one configuration (see the module docs).
struct Kinematics<T> {
    strain: [T; 6],
    frame: Quat<T>,
    /// The bushing frame as a matrix (local to global).
    axes: Mat3<T>,
    /// Node 1's orientation and the relative rotation q₁* ⊗ q₂ (w >= 0).
    q1: Quat<T>,
    rel: Quat<T>,
    /// |θ|.
    angle: T,
    /// d₁ = R₁f̄₁, d₂ = R₂f̄₂ and d = p₂ - p₁.
    d1: Vec3<T>,
    d2: Vec3<T>,
    d: Vec3<T>,
    /// R₁t (invariant form).
    half: Vec3<T>,
    /// Both orientations are unit quaternions within 1e-3.
    rotations: bool,
    /// Both positions are within a quarter of the guard.
    positions: bool,
}

impl<T: Real> Kinematics<T> {
    /// Both orientations are rotations, both positions within a quarter of
    /// [`Real::GUARD`] and the local strains within it: with offsets
    /// within a sixteenth of the guard (checked by [`SixDof::new`]), every
    /// other value the loads are formed from (the arms, d, the mid-frame
    /// terms) is then within the guard as well, so that no product of two
    /// of them, nor a force of the axes times an arm, overflows. NaN fails.
    fn usable(&self) -> bool {
        self.rotations && self.positions && all_within(&[], &self.strain, T::GUARD)
    }
}

/// The positions and orientations of both nodes are finite.
fn finite_poses<T: Real>(node1: &Pose<T>, node2: &Pose<T>) -> bool {
    [node1, node2].iter().all(|n| {
        n.position
            .iter()
            .chain(&n.orientation.v)
            .chain(core::iter::once(&n.orientation.w))
            .all(|x| x.is_finite())
    })
}

/// A 6-DOF bushing: six 1D laws, two attachment points and a
/// connectivity (see the module docs).
///
/// ```
/// use bushing::six_dof::{Connectivity, Pose, Quat, SixDof};
/// use bushing::{Bushing, ParamError, Polynomial};
///
/// // Six linear axes: 100 N/mm in translation, 1e4 N·mm/rad in rotation.
/// let axis = |k: f64| Bushing::new(Polynomial::<f64, 2>::new(&[0.0, k], (-1e3, 1e3))?, ());
/// let axes = [axis(100.0)?, axis(100.0)?, axis(100.0)?, axis(1e4)?, axis(1e4)?, axis(1e4)?];
/// let mount = SixDof::new(axes, [[0.0; 3]; 2], Connectivity::Invariant)?;
/// let at = |x: f64| Pose { position: [x, 0.0, 0.0], orientation: Quat::identity() };
/// let mut state = mount.state_at(&at(0.0), &at(0.0));
/// // Node 2 moved 1 mm along x: the bushing pulls the nodes together.
/// let out = mount.step(&mut state, &at(0.0), &at(1.0));
/// assert!((out.loads.force[0][0] - 100.0).abs() < 1e-9);
/// assert_eq!(out.loads.force[1][0], -out.loads.force[0][0]);
/// // Offsets must be finite.
/// let axes = [axis(100.0)?, axis(100.0)?, axis(100.0)?, axis(1e4)?, axis(1e4)?, axis(1e4)?];
/// assert!(SixDof::new(axes, [[f64::NAN, 0.0, 0.0], [0.0; 3]], Connectivity::Invariant).is_err());
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct SixDof<T, B, E> {
    axes: [Bushing<T, B, E>; 6],
    offsets: [Vec3<T>; 2],
    connectivity: Connectivity,
}

impl<T: Real, B: Backbone<T>, E: Effect<T>> SixDof<T, B, E> {
    /// Joins the six axis laws (translations x, y, z in length units, then
    /// rotations x, y, z in rad) attached at `offsets` (node-frame points of
    /// node 1 and node 2). Refuses an offset component that is not finite
    /// or is beyond a sixteenth of [`Real::GUARD`] (`offset[i]`, i the node
    /// and component as 3·node + component).
    pub fn new(
        axes: [Bushing<T, B, E>; 6],
        offsets: [[f64; 3]; 2],
        connectivity: Connectivity,
    ) -> Result<Self, ParamError> {
        let mut stored = [[T::ZERO; 3]; 2];
        for (n, (out, given)) in stored.iter_mut().zip(offsets).enumerate() {
            for (c, (o, g)) in out.iter_mut().zip(given).enumerate() {
                let bound = T::GUARD.to_f64() / 16.0;
                let param = Param::item("offset", 3 * n + c);
                *o = T::from_f64(in_range(param, g, -bound, false, bound)?);
            }
        }
        Ok(Self {
            axes,
            offsets: stored,
            connectivity,
        })
    }

    /// The connectivity.
    pub fn connectivity(&self) -> Connectivity {
        self.connectivity
    }

    /// The law of axis `k` (0-2 translations, 3-5 rotations).
    pub fn axis(&self, k: usize) -> Option<&Bushing<T, B, E>> {
        self.axes.get(k)
    }

    /// A relaxed state at the configuration (node 1, node 2).
    pub fn state_at(&self, node1: &Pose<T>, node2: &Pose<T>) -> SixDofState<T, E::State> {
        let k = self.kinematics(node1, node2);
        let usable = k.usable();
        let mut strain = k.strain.into_iter();
        let axes = self.axes.each_ref().map(|axis| {
            let x = strain.next().unwrap_or(T::ZERO);
            axis.state_at(if usable { x } else { T::ZERO })
        });
        let mut state = SixDofState {
            axes,
            loads: Loads {
                force: [[T::ZERO; 3]; 2],
                moment: [[T::ZERO; 3]; 2],
            },
            faults: Faults::NONE,
        };
        if usable {
            state.loads = self.loads(&k, &state.axes.each_ref().map(|a| a.force()));
        } else {
            state.faults.raise(Faults::NON_FINITE_INPUT);
        }
        state
    }

    #[inline(always)]
    fn kinematics(&self, node1: &Pose<T>, node2: &Pose<T>) -> Kinematics<T> {
        let two = T::ONE + T::ONE;
        let (q1, q2) = (node1.orientation, node2.orientation);
        // |q|² within 1e-3 of one: a rotation (NaN fails).
        let tolerance = T::from_f64(1e-3);
        let off = |q: Quat<T>| q.w * q.w + dot(q.v, q.v) - T::ONE;
        let rotations = all_within(&[], &[off(q1), off(q2)], tolerance);
        let quarter = T::GUARD * T::HALF * T::HALF;
        let ([a, b, c], [d, e, f]) = (node1.position, node2.position);
        let positions = all_within(&[], &[a, b, c, d, e, f], quarter);
        // Relative rotation, node-1 components; the shortest arc.
        let mut q = q1.conj_mul(q2);
        if q.w < T::ZERO {
            q = Quat {
                w: -q.w,
                v: neg(q.v),
            };
        }
        // θ = 2 atan2(|v|, w) v/|v|, with 1/|v| from `rsqrt` (no division,
        // no libm square root); 2v, and |θ| counted as zero, where |v|² is
        // not a normal number (|θ| < 3e-19 in f32).
        let s2 = dot(q.v, q.v);
        let (k, angle) = if s2 > min_positive::<T>() {
            let inverse = rsqrt(s2);
            let angle = two * (s2 * inverse).atan2(q.w);
            (angle * inverse, angle)
        } else {
            (two, T::ZERO)
        };
        let theta = scale(q.v, k);
        let [o1, o2] = self.offsets;
        let d1 = q1.rotate(o1);
        let d2 = q2.rotate(o2);
        let d = sub(add(node2.position, d2), add(node1.position, d1));
        let (frame, axes, half) = match self.connectivity {
            Connectivity::Attached => (q1, q1.matrix(), [T::ZERO; 3]),
            Connectivity::Invariant => {
                // R̃ = exp(½θ×) = (1 + w, v) r with r = 1/√(2(1 + w)),
                // 1 + w >= 1; t = v/(1 + w) = 2 r² v. t lies on R̃'s axis,
                // so R₁t = R₁R̃t = R̂t: the mid frame's matrix turns it.
                let r = rsqrt(two * (T::ONE + q.w));
                let tilde = Quat {
                    w: (T::ONE + q.w) * r,
                    v: scale(q.v, r),
                };
                let frame = q1 * tilde;
                let axes = frame.matrix();
                (frame, axes, mul_vec(&axes, scale(q.v, two * r * r)))
            }
        };
        let local = mul_t_vec(&axes, d);
        Kinematics {
            strain: [local[0], local[1], local[2], theta[0], theta[1], theta[2]],
            frame,
            axes,
            q1,
            rel: q,
            angle,
            rotations,
            positions,
            d1,
            d2,
            d,
            half,
        }
    }

    /// One step to the configuration (node 1, node 2). A configuration
    /// with a position that is not finite or is beyond a quarter of
    /// [`Real::GUARD`], a local strain beyond the guard, or an orientation
    /// that is not a unit quaternion within 1e-3, is refused: the axes keep
    /// their states, the last loads are returned with no dissipation, and
    /// [`Faults::NON_FINITE_INPUT`] (a NaN or infinite input) or
    /// [`Faults::OUT_OF_RANGE`] is raised in the state.
    pub fn step(
        &self,
        state: &mut SixDofState<T, E::State>,
        node1: &Pose<T>,
        node2: &Pose<T>,
    ) -> SixDofOutput<T> {
        let k = self.kinematics(node1, node2);
        if !k.usable() {
            state.faults.raise(if finite_poses(node1, node2) {
                Faults::OUT_OF_RANGE
            } else {
                Faults::NON_FINITE_INPUT
            });
            return SixDofOutput {
                loads: state.loads,
                strain: state.axes.each_ref().map(|a| a.x()),
                local: state.axes.each_ref().map(|a| a.force()),
                tangent: state.axes.each_ref().map(|a| a.tangent()),
                frame: k.frame,
                dissipated: T::ZERO,
            };
        }
        let (mut local, mut tangent) = ([T::ZERO; 6], [T::ZERO; 6]);
        let mut dissipated = T::ZERO;
        for ((((axis, s), x), f), t) in self
            .axes
            .iter()
            .zip(state.axes.iter_mut())
            .zip(k.strain)
            .zip(local.iter_mut())
            .zip(tangent.iter_mut())
        {
            let o = axis.step_within(s, x);
            *f = o.force;
            *t = o.tangent;
            dissipated += o.dissipated;
        }
        let loads = self.loads(&k, &local);
        state.loads = loads;
        SixDofOutput {
            loads,
            strain: k.strain,
            local,
            tangent,
            frame: k.frame,
            dissipated,
        }
    }

    /// The node loads of the local loads `local` (F̄, M̄) at `k`.
    #[inline(always)]
    fn loads(&self, k: &Kinematics<T>, local: &[T; 6]) -> Loads<T> {
        let force = mul_vec(&k.axes, [local[0], local[1], local[2]]);
        let moment = mul_vec(&k.axes, [local[3], local[4], local[5]]);
        match self.connectivity {
            Connectivity::Attached => Loads {
                force: [force, neg(force)],
                moment: [
                    add(cross(add(k.d, k.d1), force), moment),
                    sub(neg(cross(k.d2, force)), moment),
                ],
            },
            Connectivity::Invariant => {
                // Ĩ c = ½(c - h × c), Ĩᵀ c = ½(c + h × c).
                let c = cross(k.d, force);
                let hc = cross(k.half, c);
                let (to1, to2) = (scale(sub(c, hc), T::HALF), scale(add(c, hc), T::HALF));
                Loads {
                    force: [force, neg(force)],
                    moment: [
                        add(add(cross(k.d1, force), to1), moment),
                        sub(sub(to2, cross(k.d2, force)), moment),
                    ],
                }
            }
        }
    }

    /// The consistent tangent of the node loads at the configuration
    /// (node 1, node 2), with the axis loads and algorithmic tangents of
    /// `out` (the step or trial to that configuration): `K[i][j]` is the
    /// derivative of load i, ordered (f₁, m₁, f₂, m₂), with respect to
    /// motion j, ordered (δx₁, a, δx₂, b), a and b the global virtual
    /// rotations of the nodes (δR = (a×)R). The geometric terms (the
    /// turning frame, the arms and, in the invariant form, the moving mid
    /// point) are included; the matrix is not symmetric in general (the
    /// moment of an anisotropic law is not the gradient of a potential in
    /// either form). The formulas are in the `tangent` module source.
    ///
    /// `None` when there is no tangent to give: the configuration is one
    /// [`SixDof::step`] refuses (a NaN or huge position, an orientation
    /// that is not a rotation), or an entry would not be finite in the
    /// working type. The matrix returned never holds a NaN or an infinity;
    /// after a refused step, ask again at the last accepted configuration.
    pub fn tangent(
        &self,
        out: &SixDofOutput<T>,
        node1: &Pose<T>,
        node2: &Pose<T>,
    ) -> Option<[[T; 12]; 12]> {
        let k = self.kinematics(node1, node2);
        if !k.usable() || !out.local.iter().chain(&out.tangent).all(|v| v.is_finite()) {
            return None;
        }
        let m = tangent::tangent(self.connectivity, &k, out);
        m.iter().flatten().all(|v| v.is_finite()).then_some(m)
    }

    /// The step without committing it: the output and the state it would
    /// leave.
    pub fn trial(
        &self,
        state: &SixDofState<T, E::State>,
        node1: &Pose<T>,
        node2: &Pose<T>,
    ) -> (SixDofOutput<T>, SixDofState<T, E::State>) {
        let mut next = state.clone();
        let out = self.step(&mut next, node1, node2);
        (out, next)
    }
}

mod tangent;
#[cfg(test)]
mod tests;
