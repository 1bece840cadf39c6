//! Iwan banks: cells from `IwanCellSpec::new` or `from_slip_distance`, or
//! discretised (`iwan_from_relaxation` of an STS law or a K_f table,
//! `Segalman::discretize`, uniform or logarithmic placement); each cell's
//! own constructor (`ClampCell`, `SliderCell`); both bank forms
//! (`IwanBank`, `IwanSliders`) of one, three or eight cells.

use arbitrary::{Result, Unstructured};
use bushing::discretize::{Jenkins, Placement, Segalman, iwan_from_relaxation, total_stiffness};
use bushing::iwan::{ClampCell, SliderCell};
use bushing::{IwanBank, IwanCellSpec, IwanSliders, ParamError};

use crate::contract::{built, drive};
use crate::draw::{backbone, decades, fraction, param};
use crate::num::Num;
use crate::stack::{kf_table, sts};

pub fn fuzz<T: Num>(u: &mut Unstructured<'_>) -> Result<()> {
    match u.int_in_range(0u8..=2)? {
        0 => cells::<T, 1>(u),
        1 => cells::<T, 3>(u),
        _ => cells::<T, 8>(u),
    }
}

fn cells<T: Num, const N: usize>(u: &mut Unstructured<'_>) -> Result<()> {
    let mut k_ref = decades(u, 1.0, 1e3)?;
    let mut specs = [IwanCellSpec::new(0.0, 0.0); N];
    match u.int_in_range(0u8..=4)? {
        0 => {
            for s in &mut specs {
                *s = IwanCellSpec::new(fraction(u, N)?, decades(u, 1e-2, 1e2)?);
            }
        }
        1 => {
            for s in &mut specs {
                *s = IwanCellSpec::from_slip_distance(
                    fraction(u, N)?,
                    k_ref,
                    decades(u, 1e-4, 1.0)?,
                );
            }
        }
        2..=3 => {
            let placement = placement(u)?;
            let jenkins = match u.int_in_range(0u8..=2)? {
                0 => match sts::<f64>(u)? {
                    Some(law) => {
                        iwan_from_relaxation::<_, N>(&law, decades(u, 1e-2, 10.0)?, placement)
                    }
                    None => return Ok(()),
                },
                1 => match kf_table::<f64, 6>(u)? {
                    Some(law) => {
                        iwan_from_relaxation::<_, N>(&law, decades(u, 1e-2, 10.0)?, placement)
                    }
                    None => return Ok(()),
                },
                _ => segalman::<N>(u, placement)?,
            };
            let Some(jenkins) = built(jenkins) else {
                return Ok(());
            };
            if u.arbitrary()? {
                k_ref = total_stiffness(&jenkins);
            }
            for (s, j) in specs.iter_mut().zip(&jenkins) {
                *s = j.spec(k_ref);
            }
        }
        _ => {
            // The spec's fields as given, any values.
            for s in &mut specs {
                *s = IwanCellSpec {
                    g: param(u, 0.0, 1.0)?,
                    slip_force: param(u, 0.0, 100.0)?,
                };
            }
        }
    }
    for (i, s) in specs.iter().enumerate() {
        let _ = built(ClampCell::<T>::new(*s, i));
        let _ = built(SliderCell::<T>::new(*s, k_ref, i));
    }
    let backbone = backbone::<T>(u)?;
    if let Some(bank) = built(IwanBank::<T, N>::new(&specs)) {
        drive(u, backbone, (bank,))?;
    }
    if let Some(bank) = built(IwanSliders::<T, N>::new(&specs, k_ref)) {
        drive(u, backbone, (bank,))?;
    }
    Ok(())
}

fn placement(u: &mut Unstructured<'_>) -> Result<Placement> {
    Ok(if u.arbitrary()? {
        Placement::Uniform
    } else {
        Placement::Logarithmic {
            decades: param(u, 0.5, 6.0)?,
        }
    })
}

/// Segalman's four-parameter Iwan in `N` cells (refused below two).
fn segalman<const N: usize>(
    u: &mut Unstructured<'_>,
    placement: Placement,
) -> Result<core::result::Result<[Jenkins; N], ParamError>> {
    let model = Segalman::new(
        decades(u, 1.0, 1e3)?,
        decades(u, 1.0, 1e4)?,
        param(u, -1.0, 0.0)?,
        param(u, 0.0, 2.0)?,
    );
    Ok(model.and_then(|m| {
        let _ = (m.phi_max(), m.r(), m.s(), m.cycle_energy(m.phi_max()));
        m.discretize::<N>(placement)
    }))
}
