//! A scene with a mass on the bushing: the model behind `[oscillator]`.

use bushing::{Backbone, EffectOutput, Oscillator, OscillatorState, ParamError, Real};

pub use crate::family::backbone::AnyBackbone;

use super::*;

/// A unit mass on a scene's bushing, `x'' + F(x) = f(t)`, integrated by the
/// core's [`Oscillator`] (Newmark's average acceleration with a chord
/// iteration); the inputs are the forces f.
pub(super) struct OscillatorModel<T: Real> {
    oscillator: Oscillator<T, AnyBackbone<T>, EffectList<T>>,
    state: OscillatorState<T, Vec<Slot<T>>>,
    start: (T, T),
    count: usize,
    unconverged: u32,
    /// The shift factor the Maxwell banks are tuned to.
    shift: f64,
}

impl<T: Real + 'static> OscillatorModel<T> {
    pub(super) fn boxed(
        bushing: SceneBushing<T>,
        dt: f64,
        spec: crate::scene::OscillatorSpec,
        f0: T,
    ) -> Result<Box<dyn SceneModel<T>>, ParamError> {
        let count = bushing.effects().effects().len();
        let oscillator = Oscillator::new(bushing, dt)?;
        let start = (T::from_f64(spec.p0), T::from_f64(spec.v0));
        let state = oscillator.state_at(start.0, start.1, f0);
        Ok(Box::new(Self {
            oscillator,
            state,
            start,
            count,
            unconverged: 0,
            shift: 1.0,
        }))
    }
}

impl<T: Real> SceneModel<T> for OscillatorModel<T> {
    fn shape(&self) -> Shape {
        Shape::Oscillator
    }
    fn backbone(&self) -> &AnyBackbone<T> {
        self.oscillator.restoring().backbone()
    }
    fn g0(&self) -> f64 {
        self.oscillator.restoring().g0()
    }
    fn effect_count(&self) -> usize {
        self.count
    }
    /// Steps refused by the restoring force, plus steps whose iteration
    /// did not converge.
    fn refused(&self) -> u32 {
        self.state
            .restoring()
            .rejected()
            .saturating_add(self.unconverged)
    }
    fn step_into(
        &mut self,
        inputs: &[T],
        rows: &mut Vec<StepRow<T>>,
        parts: &mut Vec<EffectOutput<T>>,
    ) {
        let g0 = T::from_f64(self.g0());
        for &f in inputs {
            let o = self.oscillator.step(&mut self.state, f);
            if !o.converged {
                self.unconverged = self.unconverged.saturating_add(1);
            }
            let restoring = self.state.restoring();
            let (f_inf, _) = self.oscillator.restoring().backbone().eval(o.p);
            rows.push(StepRow {
                x: o.p,
                force: o.force,
                tangent: restoring.tangent(),
                dissipated: o.dissipated,
                elastic: g0 * f_inf,
                refused: !o.converged,
            });
            EffectList::parts(restoring.effects(), &EffectOutput::zero(), parts);
        }
    }
    /// Steps from the scene's initial displacement and velocity (the
    /// start force is the first input); `x0` is not used.
    fn time_steps(&self, inputs: &[T], _x0: T) -> std::time::Duration {
        let f0 = inputs.first().copied().unwrap_or(T::ZERO);
        let mut state = self.oscillator.state_at(self.start.0, self.start.1, f0);
        let start = std::time::Instant::now();
        for &f in inputs {
            let o = self.oscillator.step(&mut state, f);
            std::hint::black_box((o.p, o.force, o.dissipated));
        }
        start.elapsed()
    }
    /// The restoring force re-tuned, and the oscillator built on it again
    /// (its chord slope follows the tangent at rest).
    fn retune(&mut self, a_t: f64) -> Result<(), ParamError> {
        if a_t != self.shift {
            let restoring = shifted_bushing(self.oscillator.restoring(), a_t)?;
            self.oscillator = Oscillator::new(restoring, self.oscillator.dt())?;
            self.shift = a_t;
        }
        Ok(())
    }
}
