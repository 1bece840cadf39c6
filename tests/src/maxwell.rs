//! Maxwell banks: the explicit forms refused at their limit, every
//! exponential form bounded from ω·dt = 1e-7 to 1e4, the decay rate of a
//! slow cell in f32, the tangent against a central difference, and a
//! temperature re-tune.

use bushing::{
    Bushing, Compensated, Exponentials, MaxwellBank, MaxwellForm, MaxwellSpec, ParamError,
    Polynomial, Real, ShiftFactor,
};

use crate::check::{CaseResult, at_most, holds, param};

pub(crate) fn explicit_forms_refused_at_unit_omega_dt() -> CaseResult {
    for form in [MaxwellForm::LoadExplicit, MaxwellForm::RateExplicit] {
        let r = MaxwellBank::<f32, 1>::new(form, &[MaxwellSpec::new(2000.0, 0.2)], 5e-4);
        holds(
            "explicit form refused with ExplicitUnstable",
            matches!(r, Err(ParamError::ExplicitUnstable { cell: 0, .. })),
        )?;
    }
    Ok(())
}

pub(crate) fn exponential_forms_bounded_f32() -> CaseResult {
    exponential_forms_bounded::<f32>()
}

pub(crate) fn exponential_forms_bounded_f64() -> CaseResult {
    exponential_forms_bounded::<f64>()
}

/// Every exponential form, ω·dt from 1e-7 to 1e4 by decades, under a square
/// wave: finite, and within the bound of a high-pass cell,
/// |F| <= (g0 + 2 g) max|F^inf|.
fn exponential_forms_bounded<T: Real>() -> CaseResult {
    let dt = 1e-3;
    for form in [
        MaxwellForm::LoadExponential,
        MaxwellForm::RateMidpoint,
        MaxwellForm::RateExactRamp,
    ] {
        for decade in -7..=4 {
            let h = libm::pow(10.0, decade as f64);
            let spec = [MaxwellSpec::new(h / dt, 0.6)];
            let bank = MaxwellBank::<T, 1>::new(form, &spec, dt).map_err(param)?;
            let b = Bushing::new(Polynomial::<T, 2>::linear(100.0).map_err(param)?, (bank,))
                .map_err(param)?;
            let mut s = b.state_at(T::ZERO);
            let mut worst = 0.0f64;
            for n in 0..2000 {
                let x = if (n / 7) % 2 == 0 { T::ONE } else { -T::ONE };
                let out = b.step(&mut s, x);
                holds(
                    "finite output",
                    out.force.is_finite() && out.dissipated.is_finite(),
                )?;
                worst = worst.max(out.force.to_f64().abs());
            }
            at_most(
                "|F| / (g0 + 2 g) max|F^inf|",
                worst / (100.0 * (0.4 + 1.2)),
                1.0 + 1e-6,
            )?;
        }
    }
    Ok(())
}

/// Relative error of the decay rate of the force a cell holds after a
/// unit step, at ω·dt = `h`, over `n` steps, with storage `A` (the
/// effect's own force, not the total less the static share: f32 would
/// round that difference).
pub(crate) fn decay_rate_error<A: bushing::Accumulator<f32>>(
    h: f64,
    n: usize,
) -> Result<f64, crate::check::Failure> {
    let dt = 1e-3;
    let bank = MaxwellBank::<f32, 1, A>::new(
        MaxwellForm::RateExactRamp,
        &[MaxwellSpec::new(h / dt, 0.5)],
        dt,
    )
    .map_err(param)?;
    let b =
        Bushing::new(Polynomial::<f32, 2>::linear(1.0).map_err(param)?, (bank,)).map_err(param)?;
    let mut s = b.state_at(0.0);
    let mut force = || {
        b.step(&mut s, 1.0)
            .effects
            .map_or(f64::NAN, |r| f64::from(r.0.force))
    };
    let first = force();
    let mut last = first;
    for _ in 0..n {
        last = force();
    }
    let rate = -libm::log(last / first) / n as f64;
    Ok(libm::fabs(rate / h - 1.0))
}

pub(crate) fn slow_cell_f32_decay_rate() -> CaseResult {
    // omega dt = 1e-6, relaxing after a step: decay rate within 0.1 %.
    let error = decay_rate_error::<Compensated<f32>>(1e-6, 50_000)?;
    at_most("relative decay-rate error", error, 1e-3)
}

pub(crate) fn tangent_matches_central_difference_f64() -> CaseResult {
    let specs = [
        MaxwellSpec::hz(0.05, 0.1),
        MaxwellSpec::hz(2.0, 0.15),
        MaxwellSpec::hz(40.0, 0.2),
        MaxwellSpec::hz(400.0, 0.05),
    ];
    let dt = 2e-4;
    let mut worst = 0.0f64;
    for form in MaxwellForm::ALL {
        let bank = MaxwellBank::<f64, 4>::new(form, &specs, dt).map_err(param)?;
        let bb = Polynomial::<f64, 4>::new(&[0.0, 200.0, 3.0, 8.0], (-5.0, 5.0)).map_err(param)?;
        let b = Bushing::new(bb, (bank,)).map_err(param)?;
        let mut s = b.state_at(0.0);
        for n in 0..400 {
            let x = 2.0 * libm::sin(n as f64 * 0.05) + 0.3;
            let (out, _) = b.trial(&s, x);
            let e = 1e-5;
            let (fp, _) = b.trial(&s, x + e);
            let (fm, _) = b.trial(&s, x - e);
            let fd = (fp.force - fm.force) / (2.0 * e);
            worst = worst.max((out.tangent - fd).abs() / out.tangent.abs());
            b.step(&mut s, x);
        }
    }
    at_most("relative tangent error, all forms", worst, 1e-6)
}

pub(crate) fn temperature_retune_f32<E: Exponentials<f32>>() -> CaseResult {
    // A 4-cell bank at 20 °C re-tuned in place to 10 °C (Arrhenius,
    // E_a/R = 8000 K) mid-period, a_T and the coefficients computed in f32
    // with the exponentials E: no jump larger than one ordinary step's
    // change, then the steady modulus of eq 1.8 at the reduced frequency
    // a_T ω (a_T exact, in f64) within 0.5 %.
    let (dt, per) = (1e-3f64, 200usize);
    let specs = [
        MaxwellSpec::hz(0.5, 0.1),
        MaxwellSpec::hz(2.0, 0.15),
        MaxwellSpec::hz(8.0, 0.15),
        MaxwellSpec::hz(40.0, 0.1),
    ];
    let warm = MaxwellBank::<f32, 4>::new(MaxwellForm::RateExactRamp, &specs, dt).map_err(param)?;
    let law = ShiftFactor::arrhenius(8000.0, 293.15).map_err(param)?;
    let a_t = law.at(283.15).map_err(param)?;
    let mut cold = warm.clone();
    cold.retune::<E>(law.at_in::<f32, E>(283.15).map_err(param)?)
        .map_err(param)?;
    let k = Polynomial::<f32, 2>::linear(1.0).map_err(param)?;
    let bw = Bushing::new(k, (warm,)).map_err(param)?;
    let bc = Bushing::new(k, (cold,)).map_err(param)?;
    let mut s = bw.state_at(0.0);
    let x = |n: usize| libm::sin(core::f64::consts::TAU * (n % per) as f64 / per as f64);
    let (mut largest, mut last) = (0.0f64, 0.0f64);
    let n0 = 10 * per + per / 3;
    for n in 1..=n0 {
        let f = bw.step(&mut s, x(n) as f32).force as f64;
        largest = largest.max(libm::fabs(f - last));
        last = f;
    }
    let f = bc.step(&mut s, x(n0 + 1) as f32).force as f64;
    at_most("force jump at the re-tune", libm::fabs(f - last), largest)?;
    let periods = 40;
    let (mut fr, mut fi) = (0.0f64, 0.0f64);
    for n in n0 + 2..=n0 + 1 + periods * per {
        let out = bc.step(&mut s, x(n) as f32);
        if n > n0 + 1 + (periods - 1) * per {
            let phase = core::f64::consts::TAU * (n % per) as f64 / per as f64;
            fr += 2.0 * out.force as f64 * libm::sin(phase) / per as f64;
            fi += 2.0 * out.force as f64 * libm::cos(phase) / per as f64;
        }
    }
    let w = a_t * core::f64::consts::TAU / (dt * per as f64);
    let g0 = 1.0 - specs.iter().map(|c| c.g).sum::<f64>();
    let (s_ref, l_ref) = specs.iter().fold((g0, 0.0), |(s, l), c| {
        let d = w * w + c.omega * c.omega;
        (s + c.g * w * w / d, l + c.g * w * c.omega / d)
    });
    at_most(
        "storage vs eq 1.8 at a_T w",
        libm::fabs(fr / s_ref - 1.0),
        5e-3,
    )?;
    at_most(
        "loss vs eq 1.8 at a_T w",
        libm::fabs(fi / l_ref - 1.0),
        5e-3,
    )
}
