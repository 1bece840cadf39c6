//! The configurations of the report and their errors, family by family,
//! each against a reference that is not the code under test.
//!
//! The kernels are those of the `kernel-cost` firmware (the constructors
//! of `bushing_kernels`, or the same library constructors with the same
//! numbers where the firmware builds them inline); the cost of each row is
//! joined afterwards through its [`Cost`] keys.

use std::f64::consts::TAU;

use bushing::discretize::Segalman;
use bushing::tracker::{Filter, UtParams};
use bushing::{
    Accumulator, Bushing, Compensated, Drive, Effect, MaxwellBank, MaxwellForm, MaxwellSpec,
    Multiplied, ParamError, Plain, Polynomial, Real, XfBank, XfForm, XfSpec,
};
use bushing_kernels::{DT, Noise};

use super::{Cost, Error, Key, Options, Row, refused};
use crate::fractional_report::{self, RetunePath};
use crate::{fit, iwan_report, xf_report};

/// Orders of the Maxwell banks (cells), as the firmware measures them.
pub const MAXWELL_ORDERS: [usize; 5] = [1, 2, 4, 8, 16];
/// Test frequencies of the Maxwell banks, Hz (full mode): from the
/// slowest corner to 40 samples per period at the 2 kHz step.
pub const MAXWELL_FREQUENCIES: [f64; 6] = [0.01, 0.1, 0.5, 2.0, 10.0, 50.0];
/// The same in quick mode.
pub const MAXWELL_FREQUENCIES_QUICK: [f64; 2] = [2.0, 50.0];
/// Orders of the firmware's Iwan banks (cost rows).
pub const IWAN_COST_ORDERS: [usize; 7] = [1, 2, 4, 8, 16, 32, 64];
/// Grünwald taps.
pub const GRUNWALD_TAPS: [usize; 4] = [16, 64, 256, 1024];
/// Cells of the Maxwell banks fitted to the fractional law.
pub const FIT_CELLS: [usize; 3] = [4, 8, 16];
/// The fractional band of the comparison, Hz: four decades around the
/// firmware's transition frequency of 1 Hz.
pub const FRACTIONAL_BAND_HZ: (f64, f64) = (0.01, 100.0);
/// The backbone of the firmware's drives (`bushing_kernels::polynomial`):
/// coefficients of x^0..x^3 (N, mm) and its range.
pub const BACKBONE: ([f64; 4], (f64, f64)) = ([0.0, 150.0, 0.0, 4.0], (-6.0, 6.0));
/// The x_f cell of the firmware (corner 5 Hz, g = 0.1, x_f = 0.02 mm).
pub const XF_CELL: (f64, f64, f64) = (5.0, 0.1, 0.02);
/// The firmware's sine: amplitude (mm) and samples per period.
pub const SINE: (f64, usize) = (
    bushing_kernels::input::AMPLITUDE,
    bushing_kernels::input::PERIOD,
);
/// Refinement of the f64 reference step.
pub const REFINE: usize = 64;
/// The tracker case: f0 (Hz), damping ratio, time step (s), periods.
pub const TRACKER_CASE: (f64, f64, f64, usize) = (20.0, 0.01, 1e-3, 10);
/// Error threshold of the "cheapest within" table.
pub const THRESHOLD: f64 = 0.01;

/// Name of an accumulator, as the firmware prints it.
pub trait StateName {
    /// `plain`, `multiplied` or `compensated`.
    const NAME: &'static str;
}
impl<T> StateName for Plain<T> {
    const NAME: &'static str = "plain";
}
impl<T> StateName for Multiplied<T> {
    const NAME: &'static str = "multiplied";
}
impl<T> StateName for Compensated<T> {
    const NAME: &'static str = "compensated";
}

/// The corner frequencies of the firmware's `N`-cell Maxwell bank.
pub fn maxwell_specs<const N: usize>() -> Result<[MaxwellSpec; N], Error> {
    let bank = bushing_kernels::maxwell_bank::<f32, N, Plain<f32>>(MaxwellForm::RateExactRamp)
        .map_err(refused(format!("the firmware's {N}-cell Maxwell bank")))?;
    Ok(*bank.specs())
}

/// The working type's name in the report: `fixed` for `Q16` (I16F16),
/// as the firmware prints it; the Rust name otherwise.
pub fn type_label<T: Real>() -> &'static str {
    match T::NAME {
        "I16F16" => "fixed",
        other => other,
    }
}

/// Complex modulus K = F₁/X₁ over K^∞ of a bushing with a linear backbone
/// (the firmware's stiffness, [`BACKBONE`]) and the bank `bank`, driven by
/// a sampled sine of the firmware's amplitude ([`SINE`]) at `samples` per
/// period: `warm` periods from rest, then the first harmonics of input and
/// force over `measured` whole periods. The scale matters only to fixed
/// point.
fn bank_modulus_measured<T: Real, E: Effect<T>>(
    bank: &E,
    samples: usize,
    warm: usize,
    measured: usize,
) -> (f64, f64) {
    let (k, amplitude) = (BACKBONE.0[1], SINE.0);
    let (g0, k_inf) = (1.0 - bank.fraction(), T::from_f64(k));
    let mut state = bank.rest(T::ZERO);
    let (mut last_x, mut last_f) = (T::ZERO, T::ZERO);
    // Σ x e^{-iφ} and Σ F e^{-iφ}.
    let (mut x1, mut f1) = ((0.0f64, 0.0f64), (0.0f64, 0.0f64));
    for step in 1..=samples * (warm + measured) {
        let phi = TAU * (step % samples) as f64 / samples as f64;
        let x = T::from_f64(amplitude * phi.sin());
        let f_inf = x * k_inf;
        let drive = Drive {
            x,
            dx: x - last_x,
            f_inf,
            df_inf: f_inf - last_f,
            k_inf,
        };
        (last_x, last_f) = (x, f_inf);
        let force = bank.step_force(&mut state, &drive).to_f64() + g0 * f_inf.to_f64();
        if step > samples * warm {
            let (s, c) = phi.sin_cos();
            let xv = x.to_f64() * k;
            x1 = (x1.0 + xv * c, x1.1 - xv * s);
            f1 = (f1.0 + force * c, f1.1 - force * s);
        }
    }
    let den = x1.0 * x1.0 + x1.1 * x1.1;
    (
        (f1.0 * x1.0 + f1.1 * x1.1) / den,
        (f1.1 * x1.0 - f1.0 * x1.1) / den,
    )
}

/// Largest relative complex-modulus error `|K - K(iω)| / |K(iω)|` of the
/// discrete bank (form, cells, number type, state storage) against the
/// closed form of the same continuous bank (eq 1.8, [`fit::bank_modulus`])
/// over `freqs_hz`, stepped at the firmware's `DT`.
pub fn maxwell_error<T: Real, A: Accumulator<T>, const N: usize>(
    form: MaxwellForm,
    specs: &[MaxwellSpec; N],
    freqs_hz: &[f64],
    periods: (usize, usize),
) -> Result<f64, ParamError> {
    let bank = MaxwellBank::<T, N, A>::new(form, specs, DT)?;
    let mut worst = 0.0f64;
    for &f in freqs_hz {
        let samples = (1.0 / (f * DT)).round().max(4.0) as usize;
        let omega = TAU / (samples as f64 * DT);
        let (s, l) = bank_modulus_measured::<T, _>(&bank, samples, periods.0, periods.1);
        let (s0, l0) = fit::bank_modulus(specs, omega);
        let err = (s - s0).hypot(l - l0) / s0.hypot(l0);
        worst = worst.max(if err.is_finite() { err } else { f64::INFINITY });
    }
    Ok(worst)
}

fn band_text(freqs: &[f64]) -> String {
    let lo = freqs.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = freqs.iter().copied().fold(0.0, f64::max);
    format!("{lo}-{hi} Hz ({} frequencies)", freqs.len())
}

/// Rows of one bank size, number type and state storage: every form, the
/// full step (`maxwell`) and the force-only step (`maxwell-force`, same
/// state, same error).
fn maxwell_rows<T: Real, A: Accumulator<T> + StateName, const N: usize>(
    options: &Options,
    rows: &mut Vec<Row>,
) -> Result<(), Error> {
    let specs = maxwell_specs::<N>()?;
    let freqs: &[f64] = if options.quick {
        &MAXWELL_FREQUENCIES_QUICK
    } else {
        &MAXWELL_FREQUENCIES
    };
    let periods = if options.quick { (10, 2) } else { (20, 4) };
    for form in MaxwellForm::ALL {
        let name = format!("{}/{}", form.name(), A::NAME);
        let (error, measure) = match maxwell_error::<T, A, N>(form, &specs, freqs, periods) {
            Ok(e) => (
                Some(e),
                format!("max |K-K1.8|/|K1.8|, {}", band_text(freqs)),
            ),
            Err(e) => (None, format!("refused: {e}")),
        };
        for family in ["maxwell", "maxwell-force"] {
            let key = Key::new(family, &name, N, type_label::<T>());
            rows.push(Row::new(key.clone(), error, &measure, Cost::One(key)));
        }
    }
    Ok(())
}

/// Every Maxwell row: forms × orders × {f64, f32, fixed (Q16)} × {plain,
/// multiplied, compensated}. A further number type is one more line.
fn maxwell(options: &Options, rows: &mut Vec<Row>) -> Result<(), Error> {
    macro_rules! orders {
        ($t:ty, $a:ident) => {
            maxwell_rows::<$t, $a<$t>, 1>(options, rows)?;
            maxwell_rows::<$t, $a<$t>, 2>(options, rows)?;
            maxwell_rows::<$t, $a<$t>, 4>(options, rows)?;
            maxwell_rows::<$t, $a<$t>, 8>(options, rows)?;
            maxwell_rows::<$t, $a<$t>, 16>(options, rows)?;
        };
    }
    macro_rules! states {
        ($t:ty) => {
            orders!($t, Plain);
            orders!($t, Multiplied);
            orders!($t, Compensated);
        };
    }
    states!(f64);
    states!(f32);
    states!(bushing::Q16);
    Ok(())
}

/// The firmware's fractional law (its Grünwald cell's spec).
fn fractional_spec() -> Result<bushing::FractionalSpec, Error> {
    let b = bushing_kernels::grunwald::<16>().map_err(refused("the firmware's Grünwald cell"))?;
    Ok(b.effects().0.spec())
}

/// The band of the fractional comparison, rad/s.
fn fractional_band() -> (f64, f64) {
    (TAU * FRACTIONAL_BAND_HZ.0, TAU * FRACTIONAL_BAND_HZ.1)
}

/// Largest relative error on storage or loss of the discrete `M`-cell
/// exact-ramp bank of `cells` (f32 coefficients, at `DT`) against the
/// fractional law over the band.
fn fitted_bank_error<const M: usize>(
    spec: &bushing::FractionalSpec,
    cells: &[MaxwellSpec],
) -> Result<f64, Error> {
    let cells: &[MaxwellSpec; M] = cells.try_into().map_err(|_| Error::FitCells {
        asked: M,
        got: cells.len(),
    })?;
    let bank = MaxwellBank::<f32, M>::new(MaxwellForm::RateExactRamp, cells, DT).map_err(
        refused(format!("the {M}-cell bank fitted to the fractional law")),
    )?;
    let g0 = 1.0 - cells.iter().map(|c| c.g).sum::<f64>();
    let (lo, hi) = fractional_band();
    let mut worst = 0.0f64;
    for w in fit::log_points(lo, hi, fractional_report::PER_DECADE) {
        let (s, l) = bank.branch_response(w);
        let (s0, l0) = spec.branch_modulus(w);
        let es = ((g0 + s) / (1.0 - spec.g + s0) - 1.0).abs();
        let el = (l / l0 - 1.0).abs();
        worst = worst.max(es).max(el);
    }
    Ok(worst)
}

/// Grünwald N against Maxwell banks of M cells fitted to the same law.
fn fractional(options: &Options, rows: &mut Vec<Row>) -> Result<(), Error> {
    let spec = fractional_spec()?;
    let (lo, hi) = fractional_band();
    let (flo, fhi) = FRACTIONAL_BAND_HZ;
    let measure = format!(
        "max rel. error of K' or K'' vs eq 1.21 (alpha {}, f_c {:.3} Hz), {flo}-{fhi} Hz",
        spec.alpha,
        spec.omega_c / TAU
    );
    for n in GRUNWALD_TAPS {
        let (es, el) = fractional_report::grunwald_error(&spec, n, DT, lo, hi);
        let key = Key::new("grunwald", "bushing/alpha-0.5", n, "f32");
        let mut row = Row::new(
            key.clone(),
            Some(es.max(el)),
            &format!("{measure}, scheme response"),
            Cost::One(key),
        );
        // The same cell in its own band [1/(N dt), 1/(10 dt)].
        let (blo, bhi, _) = fractional_report::grunwald_band(n, DT);
        let (bs, bl) = fractional_report::grunwald_error(&spec, n, DT, blo, bhi);
        row.detail = format!(
            "in its own band [1/(N dt), 1/(10 dt)] = {:.3}-{:.0} Hz: {:.1} %",
            blo / TAU,
            bhi / TAU,
            100.0 * bs.max(bl)
        );
        rows.push(row);
    }
    let cells: &[usize] = if options.quick {
        &FIT_CELLS[..1]
    } else {
        &FIT_CELLS
    };
    for &m in cells {
        // The fit is made at ω_c = 1 rad/s; move it to the firmware's ω_c.
        let fitted =
            fractional_report::fit_fractional(spec.alpha, m).map_err(|source| Error::Fit {
                what: format!("the {m}-cell fit to the fractional law"),
                source,
            })?;
        let scaled: Vec<MaxwellSpec> = fitted
            .cells
            .iter()
            .map(|c| MaxwellSpec::new(c.omega * spec.omega_c, c.g))
            .collect();
        let error = match m {
            4 => fitted_bank_error::<4>(&spec, &scaled)?,
            8 => fitted_bank_error::<8>(&spec, &scaled)?,
            16 => fitted_bank_error::<16>(&spec, &scaled)?,
            _ => return Err(Error::FitOrder(m)),
        };
        rows.push(Row::new(
            Key::new("fractional-fit", "rate-exact-ramp/plain", m, "f32"),
            Some(error),
            &format!("{measure}, discrete bank response"),
            Cost::Sum(vec![
                Key::new("backbone", "polynomial-4", 1, "f32"),
                Key::new("maxwell", "rate-exact-ramp/plain", m, "f32"),
            ]),
        ));
    }
    Ok(())
}

/// Iwan banks of N Jenkins cells against the continuous STS and
/// Segalman laws, uniform and logarithmic placement.
fn iwan(rows: &mut Vec<Row>) -> Result<(), Error> {
    let (f_s, k_t, chi, beta) = iwan_report::SEGALMAN;
    let phi_max = Segalman::new(f_s, k_t, chi, beta)
        .map_err(refused("the Segalman law of the Iwan table"))?
        .phi_max();
    for n in iwan_report::ORDERS {
        let cost = Cost::One(Key::new("iwan", "clamp/log", n, "f32"));
        for (name, placement) in iwan_report::PLACEMENTS {
            let error = iwan_report::sts_error(n, placement).map_err(refused(format!(
                "the {n}-cell Iwan bank ({name}) against STS"
            )))?;
            rows.push(Row::new(
                Key::new("iwan-sts", name, n, "f32"),
                Some(error),
                "max force error / max force along nested loops, vs STS on a stack (f64)",
                cost.clone(),
            ));
        }
        for (name, placement) in iwan_report::SEGALMAN_PLACEMENTS {
            let mut worst = 0.0f64;
            for frac in iwan_report::AMPLITUDES {
                let e = iwan_report::segalman_error(n, placement, frac * phi_max).map_err(
                    refused(format!("the {n}-cell Iwan bank ({name}) against Segalman")),
                )?;
                worst = worst.max(e.abs());
            }
            rows.push(Row::new(
                Key::new("iwan-segalman", name, n, "f32"),
                Some(worst),
                "max rel. error of energy per cycle, a/phi_max 1e-3..0.5, vs Segalman (f64)",
                cost.clone(),
            ));
        }
    }
    Ok(())
}

/// Force of the firmware's x_f cell over the last period of `periods` of
/// the firmware's sine, sampled at the firmware's step, computed at
/// `refine` sub-steps per step.
fn xf_trace<T: Real>(form: XfForm, refine: usize, periods: usize) -> Result<Vec<f64>, ParamError> {
    let (f, g, x_f) = XF_CELL;
    let (amplitude, per) = SINE;
    let bank = XfBank::<T, 1>::new(form, &[XfSpec::hz(f, g, x_f)], DT / refine as f64)?;
    let b = Bushing::new(Polynomial::<T, 4>::new(&BACKBONE.0, BACKBONE.1)?, (bank,))?;
    let mut s = b.state_at(T::ZERO);
    let fine = per * refine;
    let mut out = Vec::with_capacity(per);
    for k in 1..=fine * periods {
        let x = amplitude * (TAU * (k % fine) as f64 / fine as f64).sin();
        let o = b.step(&mut s, T::from_f64(x));
        if k > fine * (periods - 1) && k % refine == 0 {
            out.push(o.effects.map_or(f64::NAN, |r| r.0.force.to_f64()));
        }
    }
    Ok(out)
}

/// Largest force difference of the x_f cell over its largest reference
/// force, against the same form in f64 at a 64 times finer step.
pub fn xf_error<T: Real>(form: XfForm, periods: usize) -> Result<f64, ParamError> {
    let trial = xf_trace::<T>(form, 1, periods)?;
    let reference = xf_trace::<f64>(form, REFINE, periods)?;
    let peak = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let worst = trial
        .iter()
        .zip(&reference)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    Ok(worst / peak)
}

fn xf_rows<T: Real>(options: &Options, rows: &mut Vec<Row>) {
    let periods = if options.quick { 2 } else { 4 };
    for form in XfForm::ALL {
        let name = match form {
            XfForm::Midpoint => "midpoint",
            XfForm::ExactRamp => "exact-ramp",
        };
        let key = Key::new("xf", name, 1, type_label::<T>());
        let mut row = match xf_error::<T>(form, periods) {
            Ok(e) => Row::new(
                key.clone(),
                Some(e),
                "max |F-Fref|/max|Fref| under the firmware sine, vs f64 at a 64x finer step",
                Cost::One(key),
            ),
            Err(e) => Row::new(key.clone(), None, &format!("refused: {e}"), Cost::One(key)),
        };
        // The steady-sliding saturation (xf_report) at one x_f per step.
        if let Ok(r) = xf_report::settle::<T>(form, 1.0) {
            row.detail = format!("saturation at |dx| = x_f: {:.4} of g K x_f", r);
        }
        rows.push(row);
    }
}

/// RMS errors (relative on f0, absolute on the damping ratio) of the
/// tracker on the free decay of [`TRACKER_CASE`], acceleration sensor,
/// 40 dB SNR, start values off by 0.5 % in frequency, 0.2 points in
/// damping and 5 % in amplitude, over `seeds` noise seeds.
pub fn tracker_errors<T: Real>(filter: Filter, seeds: u64) -> Result<(f64, f64), ParamError> {
    let (f0, zeta, dt, periods) = TRACKER_CASE;
    let w0 = TAU * f0;
    let (sigma, wd) = (-zeta * w0, w0 * (1.0 - zeta * zeta).sqrt());
    let phase = 0.4;
    // Acceleration: Re[(σ + iω)² e^{(σ + iω) t + iφ}].
    let (p_re, p_im) = (sigma * sigma - wd * wd, 2.0 * sigma * wd);
    let analytic = |t: f64| {
        let e = (sigma * t).exp();
        let (c, s) = ((wd * t + phase).cos(), (wd * t + phase).sin());
        (e * (p_re * c - p_im * s), e * (p_re * s + p_im * c))
    };
    let (a0, b0) = analytic(0.0);
    let noise = a0.hypot(b0) / 2f64.sqrt() * 1e-2;
    let samples = (periods as f64 * TAU / (wd * dt)).round() as usize;
    let (mut sf, mut sz) = (0.0, 0.0);
    for seed in 0..seeds {
        let tracker = bushing_kernels::offset_tracker::<T>(dt, f0, zeta, (a0, b0), noise, filter)?;
        let mut rng = Noise::new(seed + 1);
        let mut state = tracker.start();
        for k in 1..=samples {
            let z = analytic(k as f64 * dt).0 + noise * rng.gauss();
            tracker.step(&mut state, &[T::from_f64(z)]);
        }
        let m = tracker.mode(&state, 0);
        sf += (m.frequency.to_f64() / f0 - 1.0).powi(2);
        sz += (m.damping.to_f64() - zeta).powi(2);
    }
    let n = seeds.max(1) as f64;
    Ok(((sf / n).sqrt(), (sz / n).sqrt()))
}

fn tracker_rows<T: Real>(options: &Options, rows: &mut Vec<Row>) {
    let seeds = if options.quick { 2 } else { 24 };
    let (f0, zeta, dt, periods) = TRACKER_CASE;
    for (name, filter) in [
        ("ekf/1-mode-1-acc", Filter::Ekf),
        ("ukf/1-mode-1-acc", Filter::Ukf(UtParams::default())),
    ] {
        let key = Key::new("tracker", name, 4, type_label::<T>());
        let measure = format!(
            "RMS rel. error of f0, free decay {f0} Hz, damping {zeta}, {} samples/period, \
             acceleration, 40 dB, {periods} periods, {seeds} seeds",
            (1.0 / (f0 * dt)).round()
        );
        let row = match tracker_errors::<T>(filter, seeds) {
            Ok((ef, ez)) => {
                let mut r = Row::new(key.clone(), Some(ef), &measure, Cost::One(key));
                r.detail = format!("damping RMS error {:.4} points", 100.0 * ez);
                r
            }
            Err(e) => Row::new(key.clone(), None, &format!("refused: {e}"), Cost::One(key)),
        };
        rows.push(row);
    }
}

/// Re-tuning an 8-cell bank in f32: libm and micromath exponentials, and
/// the f64 path rounded to f32.
fn retune(rows: &mut Vec<Row>) -> Result<(), Error> {
    let specs = fractional_report::retune_bank().map_err(|source| Error::Fit {
        what: "the 8-cell bank to re-tune".into(),
        source,
    })?;
    for (name, path) in [
        ("retune-8/libm", RetunePath::Libm),
        ("retune-8/micromath", RetunePath::Micromath),
        ("retune-8/f64-shifted", RetunePath::F64),
    ] {
        let mut worst = 0.0f64;
        for a_t in fractional_report::RETUNE_SHIFTS {
            let (es, el) = fractional_report::retune_error(&specs, a_t, path).map_err(refused(
                format!("the bank re-tuned to a_T = {a_t} ({name})"),
            ))?;
            worst = worst.max(es).max(el);
        }
        let key = Key::new("retune", name, 8, "f32");
        rows.push(Row::new(
            key.clone(),
            Some(worst),
            "max rel. error of K' or K'' of the re-tuned f32 bank vs the same bank in f64, \
             a_T 0.01..100, 1 mHz-400 Hz",
            Cost::One(key),
        ));
    }
    Ok(())
}

/// Kernels measured for cost only (no reference).
fn cost_only(rows: &mut Vec<Row>) {
    let iwan = IWAN_COST_ORDERS.map(|n| ("iwan", "clamp/log", n));
    for (family, name, n) in [
        ("backbone", "polynomial-4", 1),
        ("backbone", "spline-8", 1),
        ("bushing", "default/spline+4maxwell+3jenkins", 7),
        ("sts", "stack-16", 16),
    ]
    .into_iter()
    .chain(iwan)
    {
        let key = Key::new(family, name, n, "f32");
        rows.push(Row::new(key.clone(), None, "-", Cost::One(key)));
    }
}

/// Every row of the report, errors computed, costs not yet joined.
pub fn rows(options: &Options) -> Result<Vec<Row>, Error> {
    let mut rows = Vec::new();
    maxwell(options, &mut rows)?;
    fractional(options, &mut rows)?;
    iwan(&mut rows)?;
    xf_rows::<f64>(options, &mut rows);
    xf_rows::<f32>(options, &mut rows);
    tracker_rows::<f64>(options, &mut rows);
    tracker_rows::<f32>(options, &mut rows);
    retune(&mut rows)?;
    cost_only(&mut rows);
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_ramp_bank_meets_its_closed_form() {
        let specs = maxwell_specs::<4>().unwrap();
        let e = maxwell_error::<f64, Plain<f64>, 4>(
            MaxwellForm::RateExactRamp,
            &specs,
            &[2.0, 50.0],
            (10, 2),
        )
        .unwrap();
        // θ = 2π/40 at 50 Hz: sampling error about θ²/12 on the loss.
        assert!(e > 1e-4 && e < 3e-3, "{e}");
    }

    #[test]
    fn gauss_is_centred_and_unit() {
        let mut g = Noise::new(3);
        let v: Vec<f64> = (0..20_000).map(|_| g.gauss()).collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / v.len() as f64;
        assert!(
            mean.abs() < 0.03 && (var - 1.0).abs() < 0.05,
            "{mean} {var}"
        );
    }
}
