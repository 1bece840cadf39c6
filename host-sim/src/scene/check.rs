//! Each effect's table checked in the working type and turned into the
//! parameters its model is built from.

use bushing::{
    FirstLoading, FractionalSpec, IwanCellSpec, KfTable, MaxwellCell, MaxwellForm, MaxwellSpec,
    ParamError, ShiftFactor, Sts, XfForm, XfSpec,
};

use super::*;

/// Checks an effect table by building its cells in the working type `T`
/// (every parameter check of the core, including the values that leave
/// `T`).
pub(super) fn validate_effect<T: bushing::Real>(
    spec: EffectSpec,
    dt: f64,
    k_at_rest: f64,
) -> Result<Effect, String> {
    match spec {
        EffectSpec::Maxwell { form, state, cells } => {
            let form = MaxwellForm::from_name(&form).ok_or_else(|| {
                let names: Vec<_> = MaxwellForm::ALL.iter().map(|f| f.name()).collect();
                format!("form '{form}' is not one of {}", names.join(", "))
            })?;
            let storage = Storage::from_name(&state).ok_or_else(|| {
                format!("state '{state}' is not one of plain, multiplied, compensated")
            })?;
            check_count(cells.len())?;
            for (i, c) in cells.iter().enumerate() {
                if !(c.f_hz.is_finite() && c.f_hz > 0.0) {
                    return Err(format!(
                        "cells[{i}].f_hz must be finite and > 0 Hz, got {}",
                        c.f_hz
                    ));
                }
            }
            let cells: Vec<MaxwellSpec> =
                cells.iter().map(|c| MaxwellSpec::hz(c.f_hz, c.g)).collect();
            // Build each cell once to run every parameter check of the core.
            for (i, c) in cells.iter().enumerate() {
                bushing::MaxwellCell::<T>::new(form, *c, dt, i).map_err(|e| e.to_string())?;
            }
            let sum: f64 = cells.iter().map(|c| c.g).sum();
            if sum > 1.0 + 1e-12 {
                return Err(ParamError::FractionsAboveOne { sum }.to_string());
            }
            Ok(Effect::Maxwell {
                form,
                storage,
                cells,
            })
        }
        EffectSpec::Iwan { form, k_ref, cells } => {
            let slider = match form.as_str() {
                "clamp" => false,
                "slider" => true,
                other => return Err(format!("form '{other}' is not one of clamp, slider")),
            };
            let k_ref = k_ref.unwrap_or(k_at_rest);
            if !(k_ref.is_finite() && k_ref > 0.0) {
                return Err(format!("k_ref must be finite and > 0 N/mm, got {k_ref}"));
            }
            check_count(cells.len())?;
            let cells = cells
                .iter()
                .enumerate()
                .map(|(i, c)| match (c.slip_force, c.x_f) {
                    (Some(f), None) => Ok(IwanCellSpec::new(c.g, f)),
                    (None, Some(x_f)) => Ok(IwanCellSpec::from_slip_distance(c.g, k_ref, x_f)),
                    _ => Err(format!(
                        "cells[{i}]: give exactly one of slip_force (N) and x_f (mm)"
                    )),
                })
                .collect::<Result<Vec<_>, _>>()?;
            for (i, c) in cells.iter().enumerate() {
                bushing::iwan::SliderCell::<T>::new(*c, k_ref, i).map_err(|e| e.to_string())?;
            }
            Ok(Effect::Iwan {
                slider,
                k_ref,
                cells,
            })
        }
        EffectSpec::TurningPoints {
            law,
            c,
            k1,
            d,
            k,
            first_loading,
        } => {
            let first_loading = match first_loading.as_str() {
                "masing" => FirstLoading::Masing,
                "ignored" => FirstLoading::Ignored,
                other => {
                    return Err(format!(
                        "first_loading '{other}' is not one of masing, ignored"
                    ));
                }
            };
            let law = match (law.as_str(), c, k1, d, k) {
                ("sts", Some(c), Some(k1), None, None) => {
                    Sts::<T>::new(c, k1).map_err(|e| e.to_string())?;
                    Law::Sts { c, k1 }
                }
                ("sts", ..) => {
                    return Err("law 'sts' takes c (N²/mm) and k1 (N/mm), and no d or k".into());
                }
                ("table", None, None, Some(d), Some(k)) => {
                    KfTable::<T, TABLE_POINTS>::new(&d, &k).map_err(|e| e.to_string())?;
                    Law::Table { d, k }
                }
                ("table", ..) => {
                    return Err("law 'table' takes d (mm) and k (N/mm), and no c or k1".into());
                }
                (other, ..) => return Err(format!("law '{other}' is not one of sts, table")),
            };
            Ok(Effect::TurningPoints { law, first_loading })
        }
        EffectSpec::Xf { form, cells } => {
            let form = XfForm::from_name(&form)
                .ok_or_else(|| format!("form '{form}' is not one of midpoint, exact-ramp"))?;
            check_count(cells.len())?;
            let cells: Vec<XfSpec> = cells
                .iter()
                .map(|c| XfSpec::hz(c.f_hz, c.g, c.x_f))
                .collect();
            for (i, c) in cells.iter().enumerate() {
                bushing::xf::XfCell::<T>::new(*c, dt, i).map_err(|e| e.to_string())?;
            }
            Ok(Effect::Xf { form, cells })
        }
        EffectSpec::Dahl(p) => {
            bushing::Dahl::<T>::new(p.k_d, p.f_f, p.alpha).map_err(|e| e.to_string())?;
            Ok(Effect::Friction(Friction::Dahl(p)))
        }
        EffectSpec::BoucWen(p) => {
            bushing::BoucWen::<T>::new(p.alpha, p.a, p.beta, p.gamma, p.n)
                .map_err(|e| e.to_string())?;
            Ok(Effect::Friction(Friction::BoucWen(p)))
        }
        EffectSpec::Berg(p) => {
            bushing::Berg::<T>::new(p.f_max, p.x2).map_err(|e| e.to_string())?;
            Ok(Effect::Friction(Friction::Berg(p)))
        }
        EffectSpec::Fractional {
            f_c_hz,
            alpha,
            g,
            taps,
        } => {
            let taps = usize::try_from(taps)
                .ok()
                .filter(|n| FRACTIONAL_TAPS.contains(n))
                .ok_or_else(|| {
                    let menu: Vec<_> = FRACTIONAL_TAPS.iter().map(|n| n.to_string()).collect();
                    format!(
                        "taps = {taps} is not one of {} (the memory lengths a scene's fractional cell is built with)",
                        menu.join(", ")
                    )
                })?;
            if !(f_c_hz.is_finite() && f_c_hz > 0.0) {
                return Err(format!("f_c_hz must be finite and > 0 Hz, got {f_c_hz}"));
            }
            let spec = FractionalSpec::hz(f_c_hz, alpha, g);
            // Every parameter check of the core, in the working type.
            crate::model::DynGrunwald::<T>::new(spec, taps, dt).map_err(|e| e.to_string())?;
            Ok(Effect::Fractional { spec, taps })
        }
    }
}

/// Checks a `[temperature]` table against the scene's effects in the
/// working type `T`: the law and its constants, the points (finite, times
/// increasing, every temperature where the law is defined and gives a
/// finite, positive a_T), and every Maxwell cell shifted to each point's
/// a_T. Each law is monotone in T, and the history is piecewise linear, so
/// the points bound every a_T of the run. The message starts with the field
/// (`.points[2]: …`), to follow `temperature`.
pub(super) fn validate_temperature<T: bushing::Real>(
    spec: TemperatureSpec,
    effects: &[Effect],
    dt: f64,
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
    let maxwell: Vec<(usize, MaxwellForm, &[MaxwellSpec])> = effects
        .iter()
        .enumerate()
        .filter_map(|(j, e)| match e {
            Effect::Maxwell { form, cells, .. } => Some((j, *form, cells.as_slice())),
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
        for &(j, form, cells) in &maxwell {
            for (k, c) in cells.iter().enumerate() {
                let shifted = MaxwellSpec::new(c.omega / a_t, c.g);
                MaxwellCell::<T>::new(form, shifted, dt, k).map_err(|e| {
                    format!(
                        ".points[{i}]: at temperature {temp}, a_T = {a_t:e}: effects[{j}] (maxwell): {e}"
                    )
                })?;
            }
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

pub(super) fn check_count(n: usize) -> Result<(), String> {
    if n == 0 || n > MAX_CELLS {
        Err(format!("1 to {MAX_CELLS} cells expected, got {n}"))
    } else {
        Ok(())
    }
}
