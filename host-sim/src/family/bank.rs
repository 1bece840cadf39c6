//! A bank of cells with one state word each, sized at run time: the Iwan
//! slider form and the x_f bank, each stepped by its core slice kernel.

use bushing::{Drive, Effect, EffectOutput, Real};

/// A core slice kernel: advances cells `C` with one state word each.
pub type Kernel<T, C> = fn(&[C], &mut [T], &Drive<T>) -> EffectOutput<T>;

/// A bank of cells with one force-like state word each, sized at run
/// time; the scheme is the core's slice kernel for that cell type.
#[derive(Debug, Clone)]
pub struct DynBank<T, C> {
    pub(super) cells: Vec<C>,
    pub(super) kernel: Kernel<T, C>,
    /// The state word at rest is x0 (slider positions) rather than 0.
    pub(super) rest_at_x0: bool,
    pub(super) fraction: f64,
    pub(super) dt: Option<f64>,
}

impl<T: Real, C> Effect<T> for DynBank<T, C> {
    type State = Vec<T>;
    type Report = EffectOutput<T>;

    fn fraction(&self) -> f64 {
        self.fraction
    }
    fn dt(&self) -> Option<f64> {
        self.dt
    }
    fn rest(&self, x0: T) -> Vec<T> {
        vec![if self.rest_at_x0 { x0 } else { T::ZERO }; self.cells.len()]
    }
    #[inline]
    fn step(&self, state: &mut Vec<T>, drive: &Drive<T>) -> EffectOutput<T> {
        (self.kernel)(&self.cells, state, drive)
    }
    fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
        *report
    }
}
