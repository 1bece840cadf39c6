//! Each effect's table checked in the working type and turned into the
//! parameters its model is built from.

use bushing::{
    FirstLoading, IwanCellSpec, KfTable, MaxwellForm, MaxwellSpec, ParamError, Sts, XfForm, XfSpec,
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
    }
}

pub(super) fn check_count(n: usize) -> Result<(), String> {
    if n == 0 || n > MAX_CELLS {
        Err(format!("1 to {MAX_CELLS} cells expected, got {n}"))
    } else {
        Ok(())
    }
}
