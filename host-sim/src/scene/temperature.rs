//! `[temperature]` checked against the scene's Maxwell banks, as built.

use bushing::ShiftFactor;

use super::{Temperature, TemperatureSpec};
use crate::family::{AnyEffect, Tuned};

/// Checks a `[temperature]` table against the scene's effects in the
/// working type `T`: the law and its constants, the points (finite, times
/// increasing, every temperature where the law is defined and gives a
/// finite, positive a_T), and every Maxwell cell shifted to each point's
/// a_T (each bank shifted as the run will shift it). Each law is monotone in T, and the history is piecewise linear, so
/// the points bound every a_T of the run. The message starts with the field
/// (`.points[2]: …`), to follow `temperature`.
pub(super) fn validate_temperature<T: bushing::Real>(
    spec: TemperatureSpec,
    effects: &[AnyEffect<T>],
) -> Result<Temperature, String> {
    let law = match (spec.law.as_str(), spec.c1, spec.c2, spec.activation) {
        ("wlf", Some(c1), Some(c2), None) => {
            ShiftFactor::wlf(c1, c2, spec.t_ref).map_err(|e| format!(": {e}"))?
        }
        ("wlf", ..) => {
            return Err(": law 'wlf' takes c1 and c2 (K) with t_ref, and no activation".into());
        }
        ("arrhenius", None, None, Some(activation)) => {
            ShiftFactor::arrhenius(activation, spec.t_ref).map_err(|e| format!(": {e}"))?
        }
        ("arrhenius", ..) => {
            return Err(
                ": law 'arrhenius' takes activation (E_a / R, K) with t_ref (K), and no c1 or c2"
                    .into(),
            );
        }
        (other, ..) => return Err(format!(".law '{other}' is not one of wlf, arrhenius")),
    };
    let every = u64::try_from(spec.every)
        .ok()
        .filter(|&n| n >= 1)
        .ok_or_else(|| {
            format!(
                ".every must be a whole number >= 1 (steps between re-tunes), got {}",
                spec.every
            )
        })?;
    if spec.points.is_empty() {
        return Err(".points: at least one [time s, temperature] pair expected".into());
    }
    let maxwell: Vec<_> = effects
        .iter()
        .enumerate()
        .filter_map(|(j, e)| match e {
            AnyEffect::Maxwell(bank) => Some((j, bank)),
            _ => None,
        })
        .collect();
    if maxwell.is_empty() {
        return Err(
            ": the scene has no maxwell effect: a temperature history moves the \
                    corners of the Maxwell cells only"
                .into(),
        );
    }
    let mut points = Vec::with_capacity(spec.points.len());
    for (i, &[time, temp]) in spec.points.iter().enumerate() {
        if !(time.is_finite() && temp.is_finite()) {
            return Err(format!(
                ".points[{i}]: time and temperature must be finite, got [{time}, {temp}]"
            ));
        }
        if let Some(&(before, _)) = points.last()
            && time <= before
        {
            return Err(format!(
                ".points[{i}]: time {time} s is not after the time of points[{}], {before} s: the times must increase",
                i - 1
            ));
        }
        let a_t = shift_factor(&law, temp).map_err(|m| format!(".points[{i}]: {m}"))?;
        for &(j, bank) in &maxwell {
            bank.shifted(a_t).map_err(|e| {
                format!(
                    ".points[{i}]: at temperature {temp}, a_T = {a_t:e}: effects[{j}] (maxwell): {e}"
                )
            })?;
        }
        points.push((time, temp));
    }
    Ok(Temperature { law, points, every })
}

/// a_T of `law` at temperature `t`, or why there is none.
fn shift_factor(law: &ShiftFactor, t: f64) -> Result<f64, String> {
    match *law {
        ShiftFactor::Wlf { c2, t_ref, .. } if t - t_ref <= -c2 => Err(format!(
            "temperature {t} is outside the domain of the WLF law: T - t_ref must be > -c2, that is T > {}",
            t_ref - c2
        )),
        ShiftFactor::Arrhenius { .. } if t <= 0.0 => Err(format!(
            "temperature {t} is outside the domain of the Arrhenius law: T is in kelvin, > 0"
        )),
        _ => law.at(t).map_err(|_| {
            format!("temperature {t} gives a shift factor a_T that is not finite and > 0 in f64")
        }),
    }
}
