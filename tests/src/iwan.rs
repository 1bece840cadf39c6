//! Iwan banks: the reference Iwan restoring force, the energy of a cycle,
//! Madelung's return point, the slider form against the clamp form.

use bushing::{Bushing, IwanBank, IwanCellSpec, IwanSliders, Polynomial, Real};

use crate::check::{CaseResult, Failure, at_most, holds, param};

/// The restoring force of the reference Iwan oscillator.
pub type ReferenceIwan<T> = Bushing<T, Polynomial<T, 2>, (IwanBank<T, 20>,)>;

/// The reference Iwan oscillator's restoring force of seed 004 §4.1: 20
/// cells of stiffness 0.05, slip displacements 0.2 to 2, on a parallel
/// spring of 5 (K^inf = 6).
pub fn reference_iwan<T: Real>() -> Result<ReferenceIwan<T>, Failure> {
    let cells: [IwanCellSpec; 20] = core::array::from_fn(|i| {
        let phi = 0.2 + 1.8 * i as f64 / 19.0;
        IwanCellSpec::from_slip_distance(0.05 / 6.0, 6.0, phi)
    });
    Bushing::new(
        Polynomial::linear(6.0).map_err(param)?,
        (IwanBank::new(&cells).map_err(param)?,),
    )
    .map_err(param)
}

pub(crate) fn iwan_cycle_energy_f32() -> CaseResult {
    let b = reference_iwan::<f32>()?;
    for p_m in [0.5f64, 1.0, 2.0, 5.0] {
        let mut s = b.state_at(0.0);
        let n = 1000;
        let mut cycle = 0.0f64;
        for k in 0..2 * n {
            // x = p_m cos(2 pi k / n): the extremes are samples.
            let phase = core::f64::consts::TAU * k as f64 / n as f64;
            let out = b.step(&mut s, (p_m * libm::cos(phase)) as f32);
            holds("dissipated energy never negative", out.dissipated >= 0.0)?;
            if k >= n {
                cycle += out.dissipated as f64;
            }
        }
        let exact: f64 = (0..20)
            .map(|i| 0.2 + 1.8 * i as f64 / 19.0)
            .filter(|&phi| phi < p_m)
            .map(|phi| 4.0 * 0.05 * phi * (p_m - phi))
            .sum();
        at_most(
            "relative error of D = sum 4 f_i (p_m - phi_i)",
            libm::fabs(cycle / exact - 1.0),
            1e-3,
        )?;
    }
    Ok(())
}

pub(crate) fn iwan_madelung_return_f32() -> CaseResult {
    // A hardening backbone; A = 0.8 reached going up, B = -1.1, nested inner
    // loops, back to A: the force at A again, to f32 rounding.
    let specs = [
        IwanCellSpec::new(0.1, 2.0),
        IwanCellSpec::new(0.2, 10.0),
        IwanCellSpec::new(0.15, 35.0),
        IwanCellSpec::new(0.05, 60.0),
    ];
    let bb = Polynomial::<f32, 4>::new(&[0.0, 50.0, 0.0, 2.0], (-10.0, 10.0)).map_err(param)?;
    let b = Bushing::new(bb, (IwanBank::<f32, 4>::new(&specs).map_err(param)?,)).map_err(param)?;
    let mut s = b.state_at(0.0);
    let path = [-3.0f32, 0.8, -1.1, 0.5, -0.9, 0.2, -0.3, 0.6, 0.8];
    let mut x = 0.0f32;
    let mut at_a = [0.0f32; 2];
    for (i, &p) in path.iter().enumerate() {
        let n = 97;
        let mut f = 0.0;
        for k in 1..=n {
            let v = if k == n {
                p
            } else {
                x + (p - x) * k as f32 / n as f32
            };
            f = b.step(&mut s, v).force;
        }
        if i == 1 {
            at_a[0] = f;
        }
        if i == path.len() - 1 {
            at_a[1] = f;
        }
        x = p;
    }
    at_most(
        "relative force difference at the returning point",
        ((at_a[0] - at_a[1]).abs() / at_a[0].abs()) as f64,
        1e-5,
    )
}

pub(crate) fn iwan_slider_equals_clamp_f32() -> CaseResult {
    let specs = [
        IwanCellSpec::new(0.1, 3.0),
        IwanCellSpec::new(0.2, 12.0),
        IwanCellSpec::new(0.15, 40.0),
    ];
    let a = Bushing::new(
        Polynomial::<f32, 2>::linear(100.0).map_err(param)?,
        (IwanBank::<f32, 3>::new(&specs).map_err(param)?,),
    )
    .map_err(param)?;
    let b = Bushing::new(
        Polynomial::<f32, 2>::linear(100.0).map_err(param)?,
        (IwanSliders::<f32, 3>::new(&specs, 100.0).map_err(param)?,),
    )
    .map_err(param)?;
    let (mut sa, mut sb) = (a.state_at(0.0), b.state_at(0.0));
    let mut worst = 0.0f64;
    for k in 0..3000 {
        let x = 3.0 * libm::sinf(0.01 * k as f32) * libm::cosf(0.0023 * k as f32);
        let (fa, fb) = (a.step(&mut sa, x).force, b.step(&mut sb, x).force);
        worst = worst.max(((fa - fb).abs() / (1.0 + fa.abs())) as f64);
    }
    // The clamp form accumulates one rounding per step in each sticking cell
    // (at most half an ulp of a cell force below 64 N, 3.8e-6 N); over 3000
    // steps and 3 cells the worst case is 0.017 N, 6e-5 of the 300 N peak.
    // The slider form stores positions and does not accumulate.
    at_most("slider vs clamp force, relative", worst, 1e-4)
}
