//! Iwan banks of Jenkins cells (seed 000 eqs 1.30-1.32): `type = "iwan"`.
//!
//! ```toml
//! [[effects]]
//! type = "iwan"
//! form = "clamp"            # clamp (eq 1.32) or slider (eq 1.30)
//! k_ref = 150.0             # N/mm; default: the backbone's tangent at 0
//! cells = [{ g = 0.1, slip_force = 2.0 }, { g = 0.05, x_f = 0.2 }]
//! ```
//!
//! A cell gives its slip force in N, or its slip distance `x_f` in mm
//! (slip force `g k_ref x_f`).

use bushing::iwan::{self, ClampCell, Held, SliderCell};
use bushing::{Drive, Effect, EffectOutput, IwanCellSpec, ParamError, Real};
use serde::Deserialize;

use super::{AnyEffect, DynBank, Setting, check_count};
use crate::reference::{Line, Measured, compared, no};

/// `[[effects]] type = "iwan"`, as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IwanTable {
    /// Clamp or slider form.
    pub form: IwanForm,
    /// Reference stiffness in N/mm that turns slip distances into slip
    /// forces (and the slider springs); default: backbone tangent at 0.
    #[serde(default)]
    pub k_ref: Option<f64>,
    /// The cells.
    pub cells: Vec<IwanCellToml>,
}

/// The discrete form of an Iwan bank.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum IwanForm {
    /// Force saturation of each cell (eq 1.32), on the backbone's force.
    Clamp,
    /// Slider positions (eq 1.30), on springs of stiffness `g k_ref`.
    Slider,
}

/// One Jenkins cell as written: a fraction and either a slip force or a
/// slip distance.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IwanCellToml {
    /// Load fraction g.
    pub g: f64,
    /// Slip force in N.
    #[serde(default)]
    pub slip_force: Option<f64>,
    /// Slip distance from rest in mm (slip force g k_ref x_f).
    #[serde(default)]
    pub x_f: Option<f64>,
}

/// A checked Iwan bank.
#[derive(Debug, Clone, PartialEq)]
pub struct Iwan {
    /// Clamp or slider form.
    pub form: IwanForm,
    /// Reference stiffness, N/mm.
    pub k_ref: f64,
    /// The cells, with their slip forces.
    pub cells: Vec<IwanCellSpec>,
}

impl IwanTable {
    /// The reference stiffness resolved and each cell's slip force.
    pub(super) fn check(self, setting: &Setting) -> Result<Iwan, String> {
        let k_ref = self.k_ref.unwrap_or(setting.k_at_rest);
        if !(k_ref.is_finite() && k_ref > 0.0) {
            return Err(format!("k_ref must be finite and > 0 N/mm, got {k_ref}"));
        }
        check_count(self.cells.len())?;
        let cells = self
            .cells
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
        Ok(Iwan {
            form: self.form,
            k_ref,
            cells,
        })
    }
}

impl Iwan {
    /// The bank in `T`, in its form.
    pub fn build<T: Real>(&self) -> Result<AnyEffect<T>, ParamError> {
        Ok(match self.form {
            IwanForm::Clamp => AnyEffect::Clamp(iwan_clamp(&self.cells)?),
            IwanForm::Slider => AnyEffect::Sliders(iwan_sliders(&self.cells, self.k_ref)?),
        })
    }

    /// Name for reports and trace columns.
    pub fn name(&self) -> String {
        let form = match self.form {
            IwanForm::Clamp => "clamp",
            IwanForm::Slider => "slider",
        };
        format!("iwan {form} x{}", self.cells.len())
    }

    /// Masing loops of the Jenkins cells with `x_f = F_f / (g k)`, k the
    /// backbone slope (clamp) or k_ref (slider): the energy per cycle
    /// `Σ 4 F_f (A - x_f)` over the cells that slip, the half peak-to-peak
    /// force `Σ min(F_f, g k A)`, and the asymmetric inner loop.
    pub(super) fn references(&self, m: &Measured) -> Vec<Line> {
        let slider = self.form == IwanForm::Slider;
        let Some(k) = (if slider { Some(self.k_ref) } else { m.k_lin }) else {
            return no("the clamp form's Masing loop needs a linear backbone");
        };
        let which = if slider { "k_ref" } else { "backbone slope" };
        let a = m.amplitude;
        let iwan_loop = |span: f64| -> f64 {
            let a = 0.5 * span;
            self.cells
                .iter()
                .map(|c| 4.0 * c.slip_force * (a - c.slip_force / (c.g * k)).max(0.0))
                .sum()
        };
        let tip = self
            .cells
            .iter()
            .map(|c| c.slip_force.min(c.g * k * a))
            .sum();
        vec![
            compared(
                format!(
                    "energy per steady cycle, Masing loops sum 4 F_f (A - x_f), x_f = F_f / (g k), k = {which} {k} N/mm"
                ),
                "mJ",
                iwan_loop(2.0 * a),
                m.per_cycle,
            ),
            compared(
                "half peak-to-peak force, sum min(F_f, g k A)",
                "N",
                tip,
                m.swing,
            ),
            m.inner_loop(iwan_loop(crate::reference::INNER_SPAN * a)),
        ]
    }
}

/// Iwan bank, clamp form, sized at run time (the core's clamp kernel).
#[derive(Debug, Clone)]
pub struct DynIwanClamp<T> {
    cells: Vec<ClampCell<T>>,
    fraction: f64,
}

impl<T: Real> Effect<T> for DynIwanClamp<T> {
    type State = (Vec<T>, Held<T>);
    type Report = EffectOutput<T>;

    fn fraction(&self) -> f64 {
        self.fraction
    }
    fn dt(&self) -> Option<f64> {
        None
    }
    fn rest(&self, _: T) -> Self::State {
        (vec![T::ZERO; self.cells.len()], Held::default())
    }
    #[inline]
    fn step(&self, state: &mut Self::State, drive: &Drive<T>) -> EffectOutput<T> {
        iwan::step_clamp(&self.cells, &mut state.0, &mut state.1, drive)
    }
    fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
        *report
    }
}

/// Iwan bank, slider form.
pub type DynIwanSliders<T> = DynBank<T, SliderCell<T>>;

fn iwan_clamp<T: Real>(specs: &[IwanCellSpec]) -> Result<DynIwanClamp<T>, ParamError> {
    Ok(DynIwanClamp {
        cells: specs
            .iter()
            .enumerate()
            .map(|(i, s)| ClampCell::new(*s, i))
            .collect::<Result<_, _>>()?,
        fraction: specs.iter().map(|s| s.g).sum(),
    })
}

/// A run-time sized slider-form Iwan bank.
pub fn iwan_sliders<T: Real>(
    specs: &[IwanCellSpec],
    k_ref: f64,
) -> Result<DynIwanSliders<T>, ParamError> {
    Ok(DynBank {
        cells: specs
            .iter()
            .enumerate()
            .map(|(i, s)| SliderCell::new(*s, k_ref, i))
            .collect::<Result<_, _>>()?,
        kernel: iwan::step_sliders::<T>,
        rest_at_x0: true,
        fraction: specs.iter().map(|s| s.g).sum(),
        dt: None,
    })
}
