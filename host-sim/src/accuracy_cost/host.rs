//! Host cost of the firmware's kernels: ns per call by a repeated timing
//! loop (median of several runs) and, in full mode, host instructions per
//! call under valgrind's callgrind.
//!
//! Every kernel is built as the `kernel-cost` firmware builds it and
//! called as it calls it (the same sine, the same drives, the state
//! carried from call to call), keyed by the firmware's `family`, `name`,
//! `n` and `type`.

use std::collections::BTreeMap;
use std::hint::black_box;
use std::time::Instant;

use bushing::tracker::{Filter, UtParams};
use bushing::{
    Accumulator, Backbone, Bushing, Compensated, Drive, Effect, LibmExp, MaxwellBank, MaxwellForm,
    MicromathExp, Multiplied, Plain, Real, XfBank, XfForm, XfSpec,
};
use bushing_kernels::DT;
use bushing_kernels::input::Input;

use super::families::{StateName, XF_CELL, maxwell_specs, type_label};
use super::{Error, Key, refused};
use crate::cost::callgrind;

/// Calls of one pass: the firmware's sine length.
pub const CALLS: usize = 2000;

/// One kernel and a pass of `calls` calls over its input.
pub struct HostKernel {
    /// Family, name, order, number type.
    pub key: Key,
    /// Runs that many calls, the state carried over.
    pub pass: Box<dyn FnMut(usize)>,
}

fn sine() -> Vec<f32> {
    let (amplitude, period) = super::families::SINE;
    bushing_kernels::sine::<f32, CALLS>(amplitude, period).to_vec()
}

/// The drives of the firmware's sine on its polynomial backbone, in `T`
/// (widened from the f32 ones).
pub fn drives<T: Real>() -> Result<Vec<Drive<T>>, Error> {
    let poly = bushing_kernels::polynomial::<f32>().map_err(refused("the firmware's backbone"))?;
    let xs = bushing_kernels::sine::<f32, CALLS>(super::families::SINE.0, super::families::SINE.1);
    let to = |v: f32| T::from_f64(f64::from(v));
    Ok(bushing_kernels::drives(&poly, &xs)
        .iter()
        .map(|d| Drive {
            x: to(d.x),
            dx: to(d.dx),
            f_inf: to(d.f_inf),
            df_inf: to(d.df_inf),
            k_inf: to(d.k_inf),
        })
        .collect())
}

fn effect_kernel<T: Real + 'static, E: Effect<T> + 'static>(
    key: Key,
    effect: E,
    drives: Vec<Drive<T>>,
    force_only: bool,
) -> HostKernel {
    let mut state = effect.rest(T::ZERO);
    let mut at = 0usize;
    HostKernel {
        key,
        pass: Box::new(move |calls| {
            for _ in 0..calls {
                let Some(d) = drives.get(at) else {
                    at = 0;
                    continue;
                };
                at = (at + 1) % drives.len().max(1);
                if force_only {
                    black_box(effect.step_force(&mut state, black_box(d)));
                } else {
                    black_box(effect.step(&mut state, black_box(d)));
                }
            }
        }),
    }
}

fn bushing_kernel<T: Real + 'static, B: Backbone<T> + 'static, E: Effect<T> + 'static>(
    key: Key,
    b: Bushing<T, B, E>,
    xs: Vec<T>,
) -> HostKernel {
    let mut state = b.state_at(T::ZERO);
    let mut at = 0usize;
    HostKernel {
        key,
        pass: Box::new(move |calls| {
            for _ in 0..calls {
                let x = xs.get(at).copied().unwrap_or(T::ZERO);
                at = (at + 1) % xs.len().max(1);
                let o = b.step(&mut state, black_box(x));
                black_box([o.force, o.tangent, o.dissipated]);
            }
        }),
    }
}

fn maxwell_kernels<T: Real + 'static, A: Accumulator<T> + StateName + 'static, const N: usize>(
    out: &mut Vec<HostKernel>,
) -> Result<(), Error> {
    let specs = maxwell_specs::<N>()?;
    let d = drives::<T>()?;
    for form in MaxwellForm::ALL {
        let name = format!("{}/{}", form.name(), A::NAME);
        let bank = MaxwellBank::<T, N, A>::new(form, &specs, DT).map_err(refused(format!(
            "the {N}-cell Maxwell bank {name} in {}",
            type_label::<T>()
        )))?;
        out.push(effect_kernel(
            Key::new("maxwell", &name, N, type_label::<T>()),
            bank.clone(),
            d.clone(),
            false,
        ));
        out.push(effect_kernel(
            Key::new("maxwell-force", &name, N, type_label::<T>()),
            bank,
            d.clone(),
            true,
        ));
    }
    Ok(())
}

fn iwan_kernel<const N: usize>(out: &mut Vec<HostKernel>) -> Result<(), Error> {
    let bank = bushing_kernels::iwan_bank::<f32, N>()
        .map_err(refused(format!("the firmware's {N}-cell Iwan bank")))?;
    out.push(effect_kernel(
        Key::new("iwan", "clamp/log", N, "f32"),
        bank,
        drives::<f32>()?,
        false,
    ));
    Ok(())
}

fn grunwald_kernel<const N: usize>(out: &mut Vec<HostKernel>) -> Result<(), Error> {
    let b = bushing_kernels::grunwald::<N>()
        .map_err(refused(format!("the firmware's {N}-tap Grünwald cell")))?;
    out.push(bushing_kernel(
        Key::new("grunwald", "bushing/alpha-0.5", N, "f32"),
        b,
        sine(),
    ));
    Ok(())
}

fn xf_kernels<T: Real + 'static>(out: &mut Vec<HostKernel>) -> Result<(), Error> {
    let (f, g, x_f) = XF_CELL;
    for (form, name) in [
        (XfForm::Midpoint, "midpoint"),
        (XfForm::ExactRamp, "exact-ramp"),
    ] {
        let bank = XfBank::<T, 1>::new(form, &[XfSpec::hz(f, g, x_f)], DT).map_err(refused(
            format!("the firmware's x_f cell ({name}) in {}", type_label::<T>()),
        ))?;
        out.push(effect_kernel(
            Key::new("xf", name, 1, type_label::<T>()),
            bank,
            drives::<T>()?,
            false,
        ));
    }
    Ok(())
}

/// The firmware's tracker: one mode at 20 Hz, one accelerometer, 1 kHz,
/// fed a 20 Hz sine by a rotation recurrence.
fn tracker_kernels<T: Real + 'static>(out: &mut Vec<HostKernel>) -> Result<(), Error> {
    for (name, filter) in [
        ("ekf/1-mode-1-acc", Filter::Ekf),
        ("ukf/1-mode-1-acc", Filter::Ukf(UtParams::default())),
    ] {
        let tracker = bushing_kernels::modal_tracker::<T>(filter).map_err(refused(format!(
            "the firmware's tracker ({name}) in {}",
            type_label::<T>()
        )))?;
        let mut state = tracker.start();
        let (c, s) = (
            T::from_f64((std::f64::consts::TAU * 0.02).cos()),
            T::from_f64((std::f64::consts::TAU * 0.02).sin()),
        );
        let (mut re, mut im) = (T::ONE, T::ZERO);
        out.push(HostKernel {
            key: Key::new("tracker", name, 4, type_label::<T>()),
            pass: Box::new(move |calls| {
                for _ in 0..calls {
                    let r = c * re - s * im;
                    im = s * re + c * im;
                    re = r;
                    black_box(tracker.step(&mut state, &[black_box(re)]));
                }
            }),
        });
    }
    Ok(())
}

/// The family of the default bushing's host timings on each input
/// ([`by_input`]); the name is the input's.
pub const BY_INPUT: &str = "bushing-by-input";

/// The default bushing on each of the firmware's three inputs (the large
/// sine, the small one and band-limited noise, `bushing_kernels::input`),
/// keyed `(BY_INPUT, input, 7, "f32")`: the host bound is judged on the
/// worst of them.
pub fn by_input() -> Result<Vec<HostKernel>, Error> {
    Input::ALL
        .into_iter()
        .map(|input| {
            Ok(bushing_kernel(
                Key::new(BY_INPUT, input.name(), 7, "f32"),
                bushing_kernels::default_bushing::<f32>()
                    .map_err(refused("the default bushing"))?,
                input.xs::<f32, CALLS>().to_vec(),
            ))
        })
        .collect()
}

/// Re-tuning the firmware's 8-cell bank, a_T from 1 upwards.
fn retune_kernels(out: &mut Vec<HostKernel>) -> Result<(), Error> {
    for (name, path) in [
        ("retune-8/libm", 0u8),
        ("retune-8/micromath", 1),
        ("retune-8/f64-shifted", 2),
    ] {
        let mut bank =
            bushing_kernels::maxwell_bank::<f32, 8, Plain<f32>>(MaxwellForm::RateExactRamp)
                .map_err(refused("the firmware's 8-cell bank to re-tune"))?;
        let mut k = 0u32;
        out.push(HostKernel {
            key: Key::new("retune", name, 8, "f32"),
            pass: Box::new(move |calls| {
                for _ in 0..calls {
                    k = (k + 1) % 200;
                    let a_t = 1.0 + black_box(k as f32) * 1e-2;
                    let r = match path {
                        0 => bank.retune::<LibmExp>(a_t),
                        1 => bank.retune::<MicromathExp>(a_t),
                        _ => bank.shifted(f64::from(a_t)).map(|b| {
                            bank = b;
                        }),
                    };
                    let _ = black_box(r);
                }
            }),
        });
    }
    Ok(())
}

/// Every host kernel, in a fixed order.
pub fn kernels() -> Result<Vec<HostKernel>, Error> {
    let mut out = Vec::new();
    macro_rules! maxwell {
        ($t:ty) => {
            maxwell!($t, Plain);
            maxwell!($t, Multiplied);
            maxwell!($t, Compensated);
        };
        ($t:ty, $a:ident) => {
            maxwell_kernels::<$t, $a<$t>, 1>(&mut out)?;
            maxwell_kernels::<$t, $a<$t>, 2>(&mut out)?;
            maxwell_kernels::<$t, $a<$t>, 4>(&mut out)?;
            maxwell_kernels::<$t, $a<$t>, 8>(&mut out)?;
            maxwell_kernels::<$t, $a<$t>, 16>(&mut out)?;
        };
    }
    maxwell!(f64);
    maxwell!(f32);
    maxwell!(bushing::Q16);
    iwan_kernel::<1>(&mut out)?;
    iwan_kernel::<2>(&mut out)?;
    iwan_kernel::<4>(&mut out)?;
    iwan_kernel::<8>(&mut out)?;
    iwan_kernel::<16>(&mut out)?;
    iwan_kernel::<32>(&mut out)?;
    iwan_kernel::<64>(&mut out)?;
    xf_kernels::<f64>(&mut out)?;
    xf_kernels::<f32>(&mut out)?;
    let s = sine();
    let poly =
        bushing_kernels::polynomial::<f32>().map_err(refused("the firmware's polynomial"))?;
    let spline = bushing_kernels::spline::<f32>().map_err(refused("the firmware's spline"))?;
    out.push(bushing_kernel(
        Key::new("backbone", "polynomial-4", 1, "f32"),
        Bushing::new(poly, ()).map_err(refused("the polynomial backbone alone"))?,
        s.clone(),
    ));
    out.push(bushing_kernel(
        Key::new("backbone", "spline-8", 1, "f32"),
        Bushing::new(spline, ()).map_err(refused("the spline backbone alone"))?,
        s.clone(),
    ));
    out.push(bushing_kernel(
        Key::new("bushing", "default/spline+4maxwell+3jenkins", 7, "f32"),
        bushing_kernels::default_bushing::<f32>().map_err(refused("the default bushing"))?,
        s.clone(),
    ));
    out.push(bushing_kernel(
        Key::new("sts", "stack-16", 16, "f32"),
        bushing_kernels::sts16().map_err(refused("the STS stack"))?,
        s,
    ));
    grunwald_kernel::<16>(&mut out)?;
    grunwald_kernel::<64>(&mut out)?;
    grunwald_kernel::<256>(&mut out)?;
    grunwald_kernel::<1024>(&mut out)?;
    tracker_kernels::<f64>(&mut out)?;
    tracker_kernels::<f32>(&mut out)?;
    retune_kernels(&mut out)?;
    Ok(out)
}

/// The reference kernel of the host timings ([`reference_kernel`]).
pub const REFERENCE: (&str, &str, usize, &str) = ("reference", "horner-32", 32, "f64");

/// The reference kernel: Horner's rule for a fixed polynomial of degree 32
/// in f64 at each value of the firmware's sine, a chain of 32 dependent
/// multiply-adds that no change to the library touches. A host time over
/// the reference's, both from the same run, carries from one machine or
/// one load to another better than nanoseconds do.
pub fn reference_kernel() -> HostKernel {
    let xs: Vec<f64> = sine().iter().map(|&x| f64::from(x) * 0.25).collect();
    let mut k = 0usize;
    let (family, name, n, number) = REFERENCE;
    HostKernel {
        key: Key::new(family, name, n, number),
        pass: Box::new(move |calls| {
            for _ in 0..calls {
                let x = black_box(xs.get(k % xs.len().max(1)).copied().unwrap_or(0.0));
                k = k.wrapping_add(1);
                let mut acc = 1.0f64;
                for i in 0..32 {
                    acc = acc * x + 1.0 / f64::from(i + 2);
                }
                black_box(acc);
            }
        }),
    }
}

/// ns per call of the reference kernel, the faster of a timing before and
/// one after `kernels` are timed (so that a change of load in between
/// shows as little as it can).
pub fn time_with_reference(
    kernels: &mut [HostKernel],
    timing: Timing,
) -> (BTreeMap<Key, f64>, Option<f64>) {
    let mut reference = [reference_kernel()];
    let before = time_all(&mut reference, timing);
    let ns = time_all(kernels, timing);
    let after = time_all(&mut reference, timing);
    let key = &reference[0].key;
    let best = match (before.get(key), after.get(key)) {
        (Some(a), Some(b)) => Some(a.min(*b)),
        (a, b) => a.or(b).copied(),
    };
    (ns, best)
}

/// How long to time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Timing {
    /// Calls per timed run.
    pub calls: usize,
    /// Runs, the median kept.
    pub runs: usize,
}

/// ns per call of each kernel: one warm-up pass, then the median of
/// `timing.runs` timed passes of `timing.calls` calls.
pub fn time_all(kernels: &mut [HostKernel], timing: Timing) -> BTreeMap<Key, f64> {
    let mut out = BTreeMap::new();
    for k in kernels.iter_mut() {
        (k.pass)(timing.calls);
        let mut runs: Vec<f64> = (0..timing.runs.max(1))
            .map(|_| {
                let t = Instant::now();
                (k.pass)(timing.calls);
                t.elapsed().as_secs_f64() * 1e9 / timing.calls.max(1) as f64
            })
            .collect();
        runs.sort_by(f64::total_cmp);
        if let Some(&m) = runs.get(runs.len() / 2) {
            out.insert(k.key.clone(), m);
        }
    }
    out
}

/// The function callgrind counts in: one pass of a kernel.
#[inline(never)]
pub fn accuracy_cost_collected(pass: &mut dyn FnMut(usize), calls: usize) -> usize {
    pass(calls);
    // A use after the call: no tail call, so callgrind sees the return.
    black_box(calls)
}

/// Callgrind dumps its counts when this returns (a function of its own:
/// callgrind applies one option per function, and the one inside it
/// toggles the collection).
#[inline(never)]
pub fn accuracy_cost_dumped(pass: &mut dyn FnMut(usize), calls: usize) -> usize {
    black_box(accuracy_cost_collected(pass, calls))
}

/// The hidden command that counts every kernel under callgrind:
/// `PART_COMMAND CALLS` ([`run_part`]).
pub const PART_COMMAND: &str = "accuracy-cost-part";

/// The hidden [`PART_COMMAND`], run under callgrind: prints each kernel's
/// key, warms it up, then runs one pass of `calls` calls inside
/// [`accuracy_cost_collected`] (one callgrind dump each, on leaving
/// [`accuracy_cost_dumped`]).
pub fn run_part(calls: usize) -> Result<(), Error> {
    let mut kernels = kernels()?;
    for k in &mut kernels {
        println!("{}", k.key.to_word());
        (k.pass)(calls);
        black_box(accuracy_cost_dumped(&mut *k.pass, calls));
    }
    Ok(())
}

/// Host instructions per call of every kernel: this program's hidden
/// [`PART_COMMAND`] under callgrind, counting only
/// [`accuracy_cost_collected`] and dumping after each of its calls.
pub fn instructions(calls: usize) -> Result<BTreeMap<Key, f64>, Error> {
    let args = [PART_COMMAND.into(), calls.to_string().into()];
    let counted = callgrind::count(
        &args,
        "accuracy_cost_collected",
        Some("accuracy_cost_dumped"),
    )?;
    let keys: Vec<Key> = counted.stdout.lines().filter_map(Key::from_word).collect();
    if counted.totals.len() < keys.len() {
        return Err(Error::MissingDumps {
            kernels: keys.len(),
            dumps: counted.totals.len(),
        });
    }
    Ok(keys
        .into_iter()
        .zip(counted.totals)
        .map(|(key, total)| (key, total as f64 / calls.max(1) as f64))
        .collect())
}
