//! Iwan banks: parallel Jenkins cells (spring in series with a Coulomb
//! slider), seed 000 §1.4.2 and seed 004 §2.3.
//!
//! Two forms, one per reading of the thesis:
//!
//! - [`IwanBank`], **force saturation (clamp)**, eq 1.32 with the backbone
//!   coupling of eq 1.35: a sticking cell takes the fraction g_i of every
//!   backbone increment, `Ḟ^i = g_i Ḟ^∞`, and a cell whose force reaches its
//!   slip force `F_f^i` stays there while the motion continues:
//!
//!   ```text
//!   F_tr = F^i_{n-1} + g_i ΔF^∞_n,    F^i_n = clamp(F_tr, -F_f^i, F_f^i)
//!   ```
//!
//!   Each cell is a stop operator applied to the monotone input F^∞(x), so
//!   the bank has return-point memory in x exactly (Madelung's rules), with
//!   no stored turning point: the cell forces are the memory.
//! - [`IwanSliders`], **slider (displacement)**, eqs 1.30-1.31: each cell
//!   has a linear spring `k_i = g_i K_ref` and a slider position x^i that
//!   moves only to keep `|x - x^i| <= x_f^i = F_f^i / k_i`:
//!
//!   ```text
//!   F^i = k_i (x - x^i)
//!   ```
//!
//!   With a linear backbone `F^∞ = K_ref x` both forms give the same force.
//!   With a nonlinear backbone they differ (the thesis's Fig. 1.16
//!   discussion): here the breakpoints stay at fixed distances in x.
//!
//! A cell is described by its fraction g_i and its slip force F_f^i (N), or
//! by its slip distance from rest x_f^i = F_f^i / (g_i K_ref)
//! ([`IwanCellSpec::from_slip_distance`]). That is the *virgin* breakpoint
//! (eq 1.34); after a reversal from sliding the cell sticks over 2 x_f^i (the
//! Masing factor 2).
//!
//! - **States**: one force (clamp) or one slider position (slider) per cell;
//!   the bushing keeps the shared F^∞_{n-1} and x_{n-1}.
//! - **Stability**: both updates are exact for the piecewise-linear input
//!   between samples, rate independent and unconditionally stable; there is
//!   no sign(ẋ) test, so noise around a turning point cannot make them
//!   chatter.
//! - **Dissipation**: slip force times slider travel, `F_f^i |F_tr - F^i_n| /
//!   (g_i K^∞)` in the clamp form (exact for a linear backbone),
//!   `F_f^i |Δx^i|` in the slider form; never negative.
//! - **Cost**: per visited cell one multiply-add and, in the clamp form, one
//!   compare of |F_tr| with the slip force for a cell that sticks (a cell
//!   that slips takes a second compare, for its side, and one multiply-add
//!   more for the energy); one division per bank by K^∞ for the energy of
//!   the clamp form. The clamp form does not visit the leading cells that
//!   sit at their slip force in the direction of motion ([`Held`]): they
//!   cost nothing until the next reversal. A bank of 16 costs 16.0 guest
//!   instructions per cell and step on a Cortex-M4F when every cell is
//!   visited and sticks (a 0.01 mm sine, its worst input), 6.8 under a 2 mm
//!   sine, force, tangent and energy included (`scripts/accuracy-cost.sh`).

use crate::bushing::{Drive, Effect, EffectOutput};
use crate::error::{Param, ParamError, positive, scaled};
use crate::real::{Real, clamp};

/// One Jenkins cell: load fraction and slip force.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IwanCellSpec {
    /// Fraction g_i of the high-frequency backbone carried while sticking.
    pub g: f64,
    /// Slip force F_f^i (N), the largest force the cell carries.
    pub slip_force: f64,
}

impl IwanCellSpec {
    /// A cell with fraction `g` and slip force `slip_force`.
    pub const fn new(g: f64, slip_force: f64) -> Self {
        Self { g, slip_force }
    }

    /// A cell that starts sliding after `x_f` of virgin loading on a
    /// backbone of reference stiffness `k_ref`: F_f = g k_ref x_f.
    pub fn from_slip_distance(g: f64, k_ref: f64, x_f: f64) -> Self {
        Self::new(g, g * k_ref * x_f)
    }

    fn check(&self, i: usize) -> Result<(f64, f64), ParamError> {
        let g = positive(Param::item("g", i), self.g)?;
        if g > 1.0 {
            return Err(ParamError::CellFractionAboveOne { cell: Some(i), g });
        }
        let f = positive(Param::item("slip_force", i), self.slip_force)?;
        Ok((g, f))
    }
}

fn fraction_sum(specs: &[IwanCellSpec]) -> Result<f64, ParamError> {
    let mut sum = 0.0;
    for (i, s) in specs.iter().enumerate() {
        sum += s.check(i)?.0;
    }
    if sum > 1.0 + 1e-12 {
        return Err(ParamError::FractionsAboveOne { sum });
    }
    Ok(sum)
}

/// Coefficients of one clamp-form cell.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ClampCell<T> {
    g: T,
    limit: T,
    /// F_f / g, for the energy.
    energy: T,
}

impl<T: Real> ClampCell<T> {
    /// Coefficients of cell `index`.
    pub fn new(spec: IwanCellSpec, index: usize) -> Result<Self, ParamError> {
        let (g, f) = spec.check(index)?;
        // Both, and the energy factor F_f / g, must fit the working type.
        scaled::<T>(Param::item("g", index), g)?;
        scaled::<T>(Param::item("slip_force", index), f)?;
        Ok(Self {
            g: T::from_f64(g),
            limit: T::from_f64(f),
            energy: T::from_f64(f / g),
        })
    }
}

/// The leading cells of a clamp bank that sit at their slip force in the
/// direction of motion: how many, their summed (signed) force and their
/// summed slip force.
///
/// Those cells need no work until the next reversal: each keeps its force
/// and slides by `g_i ΔF^∞ / K^∞` per step, dissipating `F_f^i |ΔF^∞| /
/// K^∞`. The step finds the run itself (a cell joins when it clamps in the
/// direction of motion next to the run; the run is dropped when ΔF^∞
/// changes sign or is zero), so any state is handled correctly; the run is
/// long when cells are given in ascending order of `F_f^i / g_i`, as the
/// discretisations of [`crate::discretize`] give them (the cells then
/// saturate in order: Masing's nesting).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Held<T> {
    cells: usize,
    force: T,
    limit: T,
}

impl<T: Real> Held<T> {
    /// Number of leading cells held at their slip force.
    pub fn cells(&self) -> usize {
        self.cells
    }
}

/// The state of a clamp-form bank: each cell's force and the held run.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(bound(
        serialize = "T: serde::Serialize",
        deserialize = "T: serde::Deserialize<'de> + Copy + Default"
    ))
)]
pub struct ClampState<T, const N: usize> {
    /// Force of each cell, in the order of the specs.
    #[cfg_attr(feature = "serde", serde(with = "crate::serde_array"))]
    pub forces: [T; N],
    /// The leading cells held at their slip force.
    pub held: Held<T>,
}

/// What a clamp step accumulates over the cells it visits.
struct Sweep<T> {
    force: T,
    slip: T,
    sticking: T,
    /// No cell visited so far stuck or clamped the other way.
    contiguous: bool,
    held: Held<T>,
}

impl<T: Real> Sweep<T> {
    /// One cell of eq 1.32: stick, or clamp at the slip force (and join
    /// the held run when next to it, clamped in the direction of motion).
    #[inline(always)]
    fn visit(&mut self, c: &ClampCell<T>, f: &mut T, df: T) {
        let trial = *f + c.g * df;
        // One compare decides the common case, a cell that sticks: the
        // trial force is finite and the limit positive, so this is
        // `clamp(trial, -limit, limit) == trial`.
        if trial.abs() <= c.limit {
            self.sticking += c.g;
            self.contiguous = false;
            *f = trial;
            self.force += trial;
        } else {
            let new = if trial > T::ZERO { c.limit } else { -c.limit };
            let excess = trial - new;
            self.slip += c.energy * excess.abs();
            if self.contiguous && excess * df > T::ZERO {
                self.held.cells += 1;
                self.held.force += new;
                self.held.limit += c.limit;
            } else {
                self.contiguous = false;
            }
            *f = new;
            self.force += new;
        }
    }
}

/// Advances clamp-form cells by one step (the one implementation, used by
/// [`IwanBank`] and by run-time sized banks). `forces` holds each cell's
/// force, `held` the run of leading cells at their slip force in the
/// direction of motion, which are not visited.
#[inline(always)]
pub fn step_clamp<T: Real>(
    cells: &[ClampCell<T>],
    forces: &mut [T],
    held: &mut Held<T>,
    drive: &Drive<T>,
) -> EffectOutput<T> {
    let df = drive.df_inf;
    // A held force has the sign of the motion that made it: the run holds
    // on while the motion goes on the same way. A reversal, or a
    // standstill (where a held cell sticks, for the tangent), visits every
    // cell again.
    let kept = if df * held.force <= T::ZERO {
        Held::default()
    } else {
        *held
    };
    let first = kept.cells;
    let mut sweep = Sweep {
        force: kept.force,
        // No product by the zero limit of an empty run.
        slip: if first == 0 {
            T::ZERO
        } else {
            kept.limit * df.abs()
        },
        sticking: T::ZERO,
        contiguous: true,
        held: kept,
    };
    if first == 0 {
        // Every cell: a loop of known length, unrolled for small banks.
        for (c, f) in cells.iter().zip(forces.iter_mut()) {
            sweep.visit(c, f, df);
        }
    } else {
        let active = cells.get(first..).unwrap_or(&[]);
        let states = forces.get_mut(first..).unwrap_or(&mut []);
        for (c, f) in active.iter().zip(states) {
            sweep.visit(c, f, df);
        }
    }
    let Sweep {
        force,
        slip,
        sticking,
        held: run,
        ..
    } = sweep;
    *held = run;
    EffectOutput {
        force,
        tangent: sticking * drive.k_inf,
        dissipated: slip / drive.k_inf,
    }
}

/// A bank of `N` Jenkins cells in the force-saturation (clamp) form, eqs 1.32
/// and 1.35 (see the module docs for equations, limits and cost).
///
/// ```
/// use bushing::{Bushing, IwanBank, IwanCellSpec, ParamError, Polynomial};
///
/// // Two Jenkins cells taking 10 % each, slipping at 1 N and 3 N.
/// let cells = [IwanCellSpec::new(0.1, 1.0), IwanCellSpec::new(0.1, 3.0)];
/// let backbone = Polynomial::<f32, 2>::new(&[0.0, 100.0], (-5.0, 5.0))?;
/// let bushing = Bushing::new(backbone, (IwanBank::<f32, 2>::new(&cells)?,))?;
/// let mut state = bushing.state_at(0.0);
/// let out = bushing.step(&mut state, 1.0);
/// // Both cells slip at 1 mm (10 N of stick each): 80 N elastic + 1 + 3.
/// assert_eq!(out.force, 84.0);
/// assert!(out.dissipated > 0.0);
/// // A slip force must be positive.
/// let r = IwanBank::<f32, 1>::new(&[IwanCellSpec::new(0.1, -1.0)]);
/// assert!(matches!(r, Err(ParamError::NotPositive { .. })));
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct IwanBank<T, const N: usize> {
    cells: [ClampCell<T>; N],
    fraction: f64,
}

impl<T: Real, const N: usize> IwanBank<T, N> {
    /// Builds the bank.
    pub fn new(specs: &[IwanCellSpec; N]) -> Result<Self, ParamError> {
        let fraction = fraction_sum(specs)?;
        let mut cells = [ClampCell::default(); N];
        for (i, (c, s)) in cells.iter_mut().zip(specs).enumerate() {
            *c = ClampCell::new(*s, i)?;
        }
        Ok(Self { cells, fraction })
    }
}

impl<T: Real, const N: usize> Effect<T> for IwanBank<T, N> {
    type State = ClampState<T, N>;
    type Report = EffectOutput<T>;

    fn fraction(&self) -> f64 {
        self.fraction
    }
    fn dt(&self) -> Option<f64> {
        None
    }
    fn rest(&self, _: T) -> ClampState<T, N> {
        ClampState {
            forces: [T::ZERO; N],
            held: Held::default(),
        }
    }
    #[inline(always)]
    fn step(&self, state: &mut ClampState<T, N>, drive: &Drive<T>) -> EffectOutput<T> {
        step_clamp(&self.cells, &mut state.forces, &mut state.held, drive)
    }
    #[inline(always)]
    fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
        *report
    }
}

/// Coefficients of one slider-form cell.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SliderCell<T> {
    k: T,
    reach: T,
    slip_force: T,
}

impl<T: Real> SliderCell<T> {
    /// Coefficients of cell `index` on a reference stiffness `k_ref`.
    pub fn new(spec: IwanCellSpec, k_ref: f64, index: usize) -> Result<Self, ParamError> {
        let (g, f) = spec.check(index)?;
        let k = g * positive(Param::scalar("k_ref"), k_ref)?;
        // The cell's stiffness and its reach F_f / k must fit the working
        // type.
        scaled::<T>(Param::item("g k_ref", index), k)?;
        scaled::<T>(Param::item("slip_force", index), f)?;
        scaled::<T>(Param::item("slip_force / (g k_ref)", index), f / k)?;
        Ok(Self {
            k: T::from_f64(k),
            reach: T::from_f64(f / k),
            slip_force: T::from_f64(f),
        })
    }
}

/// Advances slider-form cells by one step; `sliders` holds the positions
/// x^i (the one implementation, as [`step_clamp`]).
#[inline(always)]
pub fn step_sliders<T: Real>(
    cells: &[SliderCell<T>],
    sliders: &mut [T],
    drive: &Drive<T>,
) -> EffectOutput<T> {
    let x = drive.x;
    let mut force = T::ZERO;
    let mut sticking = T::ZERO;
    let mut work = T::ZERO;
    for (c, s) in cells.iter().zip(sliders.iter_mut()) {
        let new = clamp(*s, x - c.reach, x + c.reach);
        if new == *s {
            sticking += c.k;
        }
        work += c.slip_force * (new - *s).abs();
        *s = new;
        force += c.k * (x - new);
    }
    EffectOutput {
        force,
        tangent: sticking,
        dissipated: work,
    }
}

/// A bank of `N` Jenkins cells in the slider (displacement) form, eqs
/// 1.30-1.31 (see the module docs).
///
/// ```
/// use bushing::{Bushing, IwanCellSpec, IwanSliders, ParamError, Polynomial};
///
/// // The slider form: each cell's stiffness g k_ref, here on 100 N/mm.
/// let cells = [IwanCellSpec::new(0.1, 1.0), IwanCellSpec::new(0.1, 3.0)];
/// let backbone = Polynomial::<f32, 2>::new(&[0.0, 100.0], (-5.0, 5.0))?;
/// let bushing = Bushing::new(backbone, (IwanSliders::<f32, 2>::new(&cells, 100.0)?,))?;
/// let mut state = bushing.state_at(0.0);
/// let out = bushing.step(&mut state, 1.0);
/// assert_eq!(out.force, 84.0);
/// // The reference stiffness must be positive.
/// assert!(IwanSliders::<f32, 2>::new(&cells, 0.0).is_err());
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct IwanSliders<T, const N: usize> {
    cells: [SliderCell<T>; N],
    fraction: f64,
}

impl<T: Real, const N: usize> IwanSliders<T, N> {
    /// Builds the bank with springs `g_i k_ref`.
    pub fn new(specs: &[IwanCellSpec; N], k_ref: f64) -> Result<Self, ParamError> {
        let fraction = fraction_sum(specs)?;
        let mut cells = [SliderCell::default(); N];
        for (i, (c, s)) in cells.iter_mut().zip(specs).enumerate() {
            *c = SliderCell::new(*s, k_ref, i)?;
        }
        Ok(Self { cells, fraction })
    }
}

impl<T: Real, const N: usize> Effect<T> for IwanSliders<T, N> {
    type State = [T; N];
    type Report = EffectOutput<T>;

    fn fraction(&self) -> f64 {
        self.fraction
    }
    fn dt(&self) -> Option<f64> {
        None
    }
    /// Every slider at `x0`: the springs are unloaded.
    fn rest(&self, x0: T) -> [T; N] {
        [x0; N]
    }
    #[inline(always)]
    fn step(&self, state: &mut [T; N], drive: &Drive<T>) -> EffectOutput<T> {
        step_sliders(&self.cells, state, drive)
    }
    #[inline(always)]
    fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
        *report
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_that_leave_the_working_type_are_refused() {
        // g = 1e-45 is positive in f64 and zero in f32 (a slider's reach
        // F_f / k would be infinite). Found by the step_models fuzzer.
        let tiny = [IwanCellSpec::new(1e-45, 1.0)];
        assert!(matches!(
            IwanBank::<f32, 1>::new(&tiny),
            Err(ParamError::OutOfRange { .. })
        ));
        assert!(matches!(
            IwanSliders::<f32, 1>::new(&tiny, 150.0),
            Err(ParamError::OutOfRange { .. })
        ));
        assert!(IwanBank::<f64, 1>::new(&tiny).is_ok());
    }
    use crate::backbone::{Backbone, Polynomial};
    use crate::bushing::Bushing;
    use alloc::vec;
    use alloc::vec::Vec;
    use proptest::prelude::*;

    /// The reference Iwan of seed 004 §4.1 as slip forces on a unit stick
    /// stiffness split in 20 cells: phi_i = 0.2 + 1.8 (i-1)/19.
    fn reference_cells() -> [IwanCellSpec; 20] {
        core::array::from_fn(|i| {
            let phi = 0.2 + 1.8 * i as f64 / 19.0;
            IwanCellSpec::from_slip_distance(0.05 / 6.0, 6.0, phi)
        })
    }

    /// Total stick stiffness 1 out of K^inf = 6 (the parallel spring is 5).
    fn reference_bushing() -> Bushing<f64, Polynomial<f64, 2>, (IwanBank<f64, 20>,)> {
        Bushing::new(
            Polynomial::linear(6.0).unwrap(),
            (IwanBank::new(&reference_cells()).unwrap(),),
        )
        .unwrap()
    }

    /// The clamp form cell by cell, every cell visited: the reference the
    /// held-run skip must reproduce.
    fn visit_all(specs: &[IwanCellSpec], forces: &mut [f64], df: f64, k: f64) -> (f64, f64, f64) {
        let (mut force, mut sticking, mut slip) = (0.0, 0.0, 0.0);
        for (s, f) in specs.iter().zip(forces.iter_mut()) {
            let trial = *f + s.g * df;
            let new = trial.clamp(-s.slip_force, s.slip_force);
            if new == trial {
                sticking += s.g;
            }
            slip += s.slip_force / s.g * (trial - new).abs();
            *f = new;
            force += new;
        }
        (force, sticking * k, slip / k)
    }

    #[test]
    fn skipping_held_cells_changes_nothing_but_rounding() {
        // Ascending and shuffled slip distances; a noisy random walk with
        // reversals, holds and large excursions.
        let ascending = reference_cells();
        let mut shuffled = ascending;
        shuffled.swap(0, 7);
        shuffled.swap(3, 15);
        let k = 6.0;
        for specs in [ascending, shuffled] {
            let bank = IwanBank::<f64, 20>::new(&specs).unwrap();
            let mut state = bank.rest(0.0);
            let mut reference = [0.0; 20];
            let mut rng = 0x2545_f491_4f6c_dd1du64;
            let mut f_inf = 0.0;
            let mut max_held = 0;
            for n in 0..20_000 {
                rng ^= rng << 13;
                rng ^= rng >> 7;
                rng ^= rng << 17;
                let u = (rng >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                let drift = if (n / 500) % 2 == 0 { 0.06 } else { -0.06 };
                let df = if n % 97 == 0 { 0.0 } else { drift + 0.01 * u };
                f_inf += df;
                let drive = Drive {
                    x: f_inf / k,
                    dx: df / k,
                    f_inf,
                    df_inf: df,
                    k_inf: k,
                };
                let out = bank.step(&mut state, &drive);
                let (force, tangent, dissipated) = visit_all(&specs, &mut reference, df, k);
                assert_eq!(state.forces, reference, "step {n}");
                assert!(
                    (out.force - force).abs() <= 1e-12 * (1.0 + force.abs()),
                    "{n}"
                );
                assert_eq!(out.tangent, tangent, "step {n}");
                assert!((out.dissipated - dissipated).abs() <= 1e-12, "{n}");
                max_held = max_held.max(state.held.cells());
            }
            // The skip is exercised: with ascending cells the whole bank is
            // held on the long excursions.
            if specs == ascending {
                assert_eq!(max_held, 20);
            } else {
                assert!(max_held >= 1);
            }
        }
    }

    #[test]
    fn steady_cycle_dissipation_matches_the_masing_sum() {
        // D = sum_{phi_i < p_m} 4 f_i (p_m - phi_i), with f_i = 0.05 phi_i.
        let b = reference_bushing();
        for p_m in [0.1, 0.3, 0.5, 1.0, 1.5, 2.0, 3.0, 5.0, 10.0] {
            let mut s = b.state_at(0.0);
            let n = 2000;
            let mut cycle = 0.0;
            for k in 0..3 * n {
                let x = p_m
                    * libm::sin(
                        core::f64::consts::TAU * k as f64 / n as f64 + 0.5 * core::f64::consts::PI,
                    );
                let out = b.step(&mut s, x);
                assert!(out.dissipated >= 0.0);
                if k >= 2 * n {
                    cycle += out.dissipated;
                }
            }
            let exact: f64 = (0..20)
                .map(|i| 0.2 + 1.8 * i as f64 / 19.0)
                .filter(|&phi| phi < p_m)
                .map(|phi| 4.0 * 0.05 * phi * (p_m - phi))
                .sum();
            if exact == 0.0 {
                assert_eq!(cycle, 0.0, "p_m = {p_m}");
            } else {
                assert!(
                    (cycle / exact - 1.0).abs() < 1e-9,
                    "p_m = {p_m}: {cycle} vs {exact}"
                );
            }
        }
        // Seed 004 §4.1 tabulates D(1.0) = 0.33108 J and D(2.0) = 2.7663 J.
        let d1: f64 = (0..20)
            .map(|i| 0.2 + 1.8 * i as f64 / 19.0)
            .filter(|&p| p < 1.0)
            .map(|p| 0.2 * p * (1.0 - p))
            .sum();
        assert!((d1 - 0.33108).abs() < 1e-5);
    }

    #[test]
    fn slider_and_clamp_forms_agree_on_a_linear_backbone() {
        let specs = [
            IwanCellSpec::new(0.1, 3.0),
            IwanCellSpec::new(0.2, 12.0),
            IwanCellSpec::new(0.15, 40.0),
        ];
        let bb = || Polynomial::<f64, 2>::linear(100.0).unwrap();
        let a = Bushing::new(bb(), (IwanBank::new(&specs).unwrap(),)).unwrap();
        let b = Bushing::new(bb(), (IwanSliders::new(&specs, 100.0).unwrap(),)).unwrap();
        let (mut sa, mut sb) = (a.state_at(0.0), b.state_at(0.0));
        for k in 0..5000 {
            let t = k as f64 * 1e-3;
            let x = 4.0 * libm::sin(3.0 * t) * libm::cos(0.7 * t);
            let (oa, ob) = (a.step(&mut sa, x), b.step(&mut sb, x));
            assert!((oa.force - ob.force).abs() < 1e-9 * (1.0 + oa.force.abs()));
            assert!((oa.tangent - ob.tangent).abs() < 1e-9);
            assert!((oa.dissipated - ob.dissipated).abs() < 1e-9 * (1.0 + oa.dissipated));
        }
    }

    #[test]
    fn first_loading_breaks_at_x_f_and_reversal_at_twice_x_f() {
        let spec = [IwanCellSpec::from_slip_distance(0.5, 10.0, 0.2)]; // F_f = 1
        let b = Bushing::new(
            Polynomial::<f64, 2>::linear(10.0).unwrap(),
            (IwanBank::new(&spec).unwrap(),),
        )
        .unwrap();
        let mut s = b.state_at(0.0);
        let k0 = b.step(&mut s, 0.1).tangent;
        assert_eq!(k0, 10.0); // g0 K + g K, sticking
        assert_eq!(b.step(&mut s, 0.3).tangent, 5.0); // sliding past x_f = 0.2
        // Reverse from 0.3: sticks until 0.3 - 2 x_f = -0.1.
        assert_eq!(b.step(&mut s, 0.0).tangent, 10.0);
        assert_eq!(b.step(&mut s, -0.2).tangent, 5.0);
    }

    #[test]
    fn parameter_errors() {
        assert_eq!(
            IwanBank::<f64, 2>::new(&[IwanCellSpec::new(0.1, 1.0), IwanCellSpec::new(0.1, 0.0)]),
            Err(ParamError::NotPositive {
                param: Param::item("slip_force", 1),
                value: 0.0
            })
        );
        assert_eq!(
            IwanBank::<f64, 2>::new(&[IwanCellSpec::new(0.7, 1.0), IwanCellSpec::new(0.7, 1.0)]),
            Err(ParamError::FractionsAboveOne { sum: 1.4 })
        );
        assert_eq!(
            IwanBank::<f64, 2>::new(&[IwanCellSpec::new(0.1, 1.0), IwanCellSpec::new(1.2, 1.0)]),
            Err(ParamError::CellFractionAboveOne {
                cell: Some(1),
                g: 1.2
            })
        );
        assert!(matches!(
            IwanSliders::<f64, 1>::new(&[IwanCellSpec::new(0.1, 1.0)], -1.0),
            Err(ParamError::NotPositive { .. })
        ));
    }

    /// A path through turning points, sampled with steps of at most `h`.
    fn walk(points: &[f64], h: f64, mut visit: impl FnMut(f64, bool)) {
        let mut x = 0.0;
        for &p in points {
            let n = ((p - x).abs() / h).ceil().max(1.0) as usize;
            for k in 1..=n {
                let v = if k == n {
                    p
                } else {
                    x + (p - x) * k as f64 / n as f64
                };
                visit(v, k == n);
            }
            x = p;
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// Madelung: from turning point A to B, any inner loops strictly
        /// between them, then back to A: the force at A is the force it had.
        #[test]
        fn madelung_return_point_memory_clamp_form(
            a in -3.0f64..3.0,
            reach in 0.01f64..0.99,
            down in any::<bool>(),
            inner in prop::collection::vec(0.01f64..0.99, 0..12),
            h in 0.002f64..0.2,
            c3 in 0.0f64..3.0,
        ) {
            // B inside the current loop: between A and the reversal before it
            // (beyond it, rule 3 wipes A's loop and rule 2 no longer applies).
            let previous = if down { -4.0 } else { 4.5 };
            let b_pt = a + (previous - a) * reach;
            let specs = [
                IwanCellSpec::new(0.1, 2.0),
                IwanCellSpec::new(0.2, 10.0),
                IwanCellSpec::new(0.15, 35.0),
                IwanCellSpec::new(0.05, 60.0),
            ];
            // A hardening backbone: the coupling is through F^inf(x).
            let bb = Polynomial::<f64, 4>::new(&[0.0, 50.0, 0.0, c3], (-10.0, 10.0)).unwrap();
            let bush = Bushing::new(bb, (IwanBank::new(&specs).unwrap(),)).unwrap();
            let mut s = bush.state_at(0.0);
            // Arrive at A moving away from B, so that A is a turning point.
            let mut path = if down { vec![4.5, -4.0, a, b_pt] } else { vec![-4.0, 4.5, a, b_pt] };
            path.extend(inner.iter().map(|u| a + (b_pt - a) * u));
            path.push(a);
            let mut forces_at_a = Vec::new();
            let mut turns = 0;
            walk(&path, h, |x, at_turn| {
                let f = bush.step(&mut s, x).force;
                if at_turn {
                    turns += 1;
                    if turns == 3 || turns == path.len() {
                        forces_at_a.push(f);
                    }
                }
            });
            let (first, last) = (forces_at_a[0], forces_at_a[1]);
            prop_assert!((first - last).abs() <= 1e-9 * first.abs().max(1.0), "{} vs {}", first, last);
            prop_assert!(turns == path.len());
        }
    }

    #[test]
    fn the_backbone_is_shared_not_reevaluated() {
        // The clamp form only sees F^inf through the drive: a bank stepped
        // with a hand-made drive equals the bushing's effect output.
        let specs = [IwanCellSpec::new(0.3, 5.0)];
        let bank = IwanBank::<f64, 1>::new(&specs).unwrap();
        let bb = Polynomial::<f64, 4>::new(&[0.0, 50.0, 0.0, 1.0], (-10.0, 10.0)).unwrap();
        let bush = Bushing::new(bb, (bank.clone(),)).unwrap();
        let mut s = bush.state_at(0.0);
        let mut f = bank.rest(0.0);
        let mut prev = bb.eval(0.0).0;
        for k in 1..100 {
            let x = 0.05 * k as f64;
            let (fi, ki) = bb.eval(x);
            let d = Drive {
                x,
                dx: 0.05,
                f_inf: fi,
                df_inf: fi - prev,
                k_inf: ki,
            };
            let own = bank.step(&mut f, &d);
            let via = bush.step(&mut s, x).effects.unwrap().0;
            assert_eq!(own, via);
            prev = fi;
        }
    }
}
