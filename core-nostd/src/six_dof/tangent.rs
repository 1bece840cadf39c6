//! The consistent tangent of a 6-DOF bushing's node loads.
//!
//! With the node motions (δx₁, a, δx₂, b), a and b the global virtual
//! rotations (δR_i = (a×)R_i), the variations are (seed 002's connectivity,
//! carried through to the loads):
//!
//! - δd = δx₂ - δx₁ + d₁ × a - d₂ × b;
//! - the frame's spin: a (attached) or Ĩᵀa + Ĩb (invariant);
//! - δθ = Γ⁻¹(θ) R₁ᵀ(b - a), Γ the left Jacobian of exp on SO(3):
//!   Γ⁻¹ = I - ½θ× + γ θ×θ×, γ = (1 - (φ/2) cot(φ/2))/φ²;
//! - δF = A δd + (A d× - F×) spin, A = R_b K_t R_bᵀ;
//! - δM = R_b K_r Γ⁻¹ R₁ᵀ (b - a) - M× spin;
//! - invariant: δh = -h × a + R₁ T′ δθ, with h = R₁t, t = τ θ/φ,
//!   τ = tan(φ/4), T′ = ∂t/∂θ = (τ/φ) I + (τ′φ - τ)/φ³ θθᵀ;
//!
//! and the moments of the module docs are differentiated term by term.
//! Below φ = 0.1 the ratios use their series (the closed forms cancel).

use super::{Connectivity, Kinematics, Mat3, SixDofOutput, Vec3, add, cross, dot, scale, sub};
use crate::real::Real;

/// A 3×3 matrix by rows.
/// The variation of a 3-vector: 3 rows of 12 (δx₁, a, δx₂, b).
type Jac<T> = [[T; 12]; 3];

fn skew<T: Real>(v: Vec3<T>) -> Mat3<T> {
    let z = T::ZERO;
    [[z, -v[2], v[1]], [v[2], z, -v[0]], [-v[1], v[0], z]]
}

fn transpose<T: Real>(a: Mat3<T>) -> Mat3<T> {
    [
        [a[0][0], a[1][0], a[2][0]],
        [a[0][1], a[1][1], a[2][1]],
        [a[0][2], a[1][2], a[2][2]],
    ]
}

fn mat_mul<T: Real>(a: Mat3<T>, b: Mat3<T>) -> Mat3<T> {
    a.map(|row| {
        add(
            add(scale(b[0], row[0]), scale(b[1], row[1])),
            scale(b[2], row[2]),
        )
    })
}

fn mat_add<T: Real>(a: Mat3<T>, b: Mat3<T>) -> Mat3<T> {
    [add(a[0], b[0]), add(a[1], b[1]), add(a[2], b[2])]
}

fn mat_sub<T: Real>(a: Mat3<T>, b: Mat3<T>) -> Mat3<T> {
    [sub(a[0], b[0]), sub(a[1], b[1]), sub(a[2], b[2])]
}

fn mat_scale<T: Real>(a: Mat3<T>, k: T) -> Mat3<T> {
    a.map(|row| scale(row, k))
}

fn diag<T: Real>(d: Vec3<T>) -> Mat3<T> {
    let z = T::ZERO;
    [[d[0], z, z], [z, d[1], z], [z, z, d[2]]]
}

fn identity<T: Real>() -> Mat3<T> {
    diag([T::ONE; 3])
}

/// The outer product u vᵀ.
fn outer<T: Real>(u: Vec3<T>, v: Vec3<T>) -> Mat3<T> {
    [scale(v, u[0]), scale(v, u[1]), scale(v, u[2])]
}

/// c₀ j₀ + c₁ j₁ + c₂ j₂ (one row of a matrix times a Jac).
fn comb<T: Real>(c: Vec3<T>, j: &Jac<T>) -> [T; 12] {
    let mut out = [T::ZERO; 12];
    for (o, ((x, y), z)) in out.iter_mut().zip(j[0].iter().zip(&j[1]).zip(&j[2])) {
        *o = c[0] * *x + c[1] * *y + c[2] * *z;
    }
    out
}

fn apply<T: Real>(a: Mat3<T>, j: &Jac<T>) -> Jac<T> {
    a.map(|row| comb(row, j))
}

fn jac_zip<T: Real>(a: &Jac<T>, b: &Jac<T>, f: impl Fn(T, T) -> T) -> Jac<T> {
    let mut out = *a;
    for (o, r) in out.iter_mut().zip(b) {
        for (x, y) in o.iter_mut().zip(r) {
            *x = f(*x, *y);
        }
    }
    out
}

fn jac_add<T: Real>(a: &Jac<T>, b: &Jac<T>) -> Jac<T> {
    jac_zip(a, b, |x, y| x + y)
}

fn jac_sub<T: Real>(a: &Jac<T>, b: &Jac<T>) -> Jac<T> {
    jac_zip(a, b, |x, y| x - y)
}

/// The identity on dof block `k` (0: δx₁, 1: a, 2: δx₂, 3: b).
fn unit<T: Real>(k: usize) -> Jac<T> {
    let mut j = [[T::ZERO; 12]; 3];
    for (r, row) in j.iter_mut().enumerate() {
        if let Some(x) = row.get_mut(3 * k + r) {
            *x = T::ONE;
        }
    }
    j
}

/// Γ⁻¹(θ) and T′ = ∂t/∂θ, from the relative rotation (w = cos(φ/2),
/// |v| = sin(φ/2)) and θ.
fn rotation_jacobians<T: Real>(k: &Kinematics<T>) -> (Mat3<T>, Mat3<T>) {
    let theta = [k.strain[3], k.strain[4], k.strain[5]];
    let phi = k.angle;
    let phi2 = phi * phi;
    let c = |v: f64| T::from_f64(v);
    let (gamma, g, h) = if phi < c(0.1) {
        (
            c(1.0 / 12.0) + phi2 * (c(1.0 / 720.0) + phi2 * c(1.0 / 30240.0)),
            c(0.25) + phi2 * (c(1.0 / 192.0) + phi2 * c(1.0 / 7680.0)),
            c(1.0 / 96.0) + phi2 * c(1.0 / 1920.0),
        )
    } else {
        let s = dot(k.rel.v, k.rel.v).sqrt();
        // (φ/2) cot(φ/2) = (φ/2) w/s; τ = tan(φ/4) = s/(1 + w).
        let half_cot = T::HALF * phi * k.rel.w / s;
        let tau = s / (T::ONE + k.rel.w);
        let tau_prime = c(0.25) * (T::ONE + tau * tau);
        (
            (T::ONE - half_cot) / phi2,
            tau / phi,
            (tau_prime * phi - tau) / (phi2 * phi),
        )
    };
    let t = skew(theta);
    let gamma_inv = mat_add(
        mat_sub(identity(), mat_scale(t, T::HALF)),
        mat_scale(mat_mul(t, t), gamma),
    );
    let t_prime = mat_add(mat_scale(identity(), g), mat_scale(outer(theta, theta), h));
    (gamma_inv, t_prime)
}

/// ∂(f₁, m₁, f₂, m₂)/∂(δx₁, a, δx₂, b) at the configuration of `k`, with
/// the axis loads and tangents of `out`.
pub(super) fn tangent<T: Real>(
    connectivity: Connectivity,
    k: &Kinematics<T>,
    out: &SixDofOutput<T>,
) -> [[T; 12]; 12] {
    let l = out.local;
    let t = out.tangent;
    let rb = k.axes;
    let force = super::mul_vec(&rb, [l[0], l[1], l[2]]);
    let moment = super::mul_vec(&rb, [l[3], l[4], l[5]]);
    let r1 = k.q1.matrix();
    let (gamma_inv, t_prime) = rotation_jacobians(k);
    let (u1, a, u2, b) = (unit(0), unit(1), unit(2), unit(3));
    let rel = jac_sub(&b, &a);
    // δd = δx₂ - δx₁ + d₁ × a - d₂ × b
    let dd = jac_sub(
        &jac_add(&jac_sub(&u2, &u1), &apply(skew(k.d1), &a)),
        &apply(skew(k.d2), &b),
    );
    let i_tilde = mat_scale(mat_sub(identity(), skew(k.half)), T::HALF);
    let i_tilde_t = transpose(i_tilde);
    let spin = match connectivity {
        Connectivity::Attached => a,
        Connectivity::Invariant => jac_add(&apply(i_tilde_t, &a), &apply(i_tilde, &b)),
    };
    let stiff_t = mat_mul(mat_mul(rb, diag([t[0], t[1], t[2]])), transpose(rb));
    let stiff_r = mat_mul(
        mat_mul(mat_mul(rb, diag([t[3], t[4], t[5]])), gamma_inv),
        transpose(r1),
    );
    let (fx, mx) = (skew(force), skew(moment));
    let df = jac_add(
        &apply(stiff_t, &dd),
        &apply(mat_sub(mat_mul(stiff_t, skew(k.d)), fx), &spin),
    );
    let dm = jac_sub(&apply(stiff_r, &rel), &apply(mx, &spin));
    let (dm1, dm2) = match connectivity {
        Connectivity::Attached => {
            // m₁ = (d + d₁) × F + M, m₂ = -d₂ × F - M
            let arm = jac_sub(&dd, &apply(skew(k.d1), &a));
            let dm1 = jac_add(
                &jac_sub(&apply(skew(add(k.d, k.d1)), &df), &apply(fx, &arm)),
                &dm,
            );
            let dm2 = jac_sub(
                &jac_sub(
                    &apply(mat_scale(mat_mul(fx, skew(k.d2)), -T::ONE), &b),
                    &apply(skew(k.d2), &df),
                ),
                &dm,
            );
            (dm1, dm2)
        }
        Connectivity::Invariant => {
            // m₁ = d₁ × F + Ĩ c + M, m₂ = -d₂ × F + Ĩᵀ c - M, c = d × F,
            // Ĩ = ½(I - h×).
            let c = cross(k.d, force);
            let half_cx = mat_scale(skew(c), T::HALF);
            let to_h = mat_mul(mat_mul(mat_mul(r1, t_prime), gamma_inv), transpose(r1));
            let dh = jac_sub(&apply(to_h, &rel), &apply(skew(k.half), &a));
            let dc = jac_sub(&apply(skew(k.d), &df), &apply(fx, &dd));
            let dm1 = jac_add(
                &jac_add(
                    &jac_add(&apply(mat_mul(fx, skew(k.d1)), &a), &apply(skew(k.d1), &df)),
                    &jac_add(&apply(half_cx, &dh), &apply(i_tilde, &dc)),
                ),
                &dm,
            );
            let dm2 = jac_sub(
                &jac_add(
                    &jac_sub(
                        &apply(mat_scale(mat_mul(fx, skew(k.d2)), -T::ONE), &b),
                        &apply(skew(k.d2), &df),
                    ),
                    &jac_sub(&apply(i_tilde_t, &dc), &apply(half_cx, &dh)),
                ),
                &dm,
            );
            (dm1, dm2)
        }
    };
    let df2 = jac_sub(&[[T::ZERO; 12]; 3], &df);
    let mut rows = [[T::ZERO; 12]; 12];
    for (row, src) in rows
        .iter_mut()
        .zip(df.iter().chain(&dm1).chain(&df2).chain(&dm2))
    {
        *row = *src;
    }
    rows
}
