//! Properties that must hold for any parameters and any displacement
//! history (proptest), on a bushing with every kind of effect: a hardening
//! backbone, Maxwell cells, Jenkins cells, an x_f cell and a friction cell,
//! in f32 and f64.
//!
//! - passivity: the energy dissipated over any closed displacement cycle,
//!   and in every single step, is not negative;
//! - boundedness: the force stays within the backbone's elastic share plus
//!   each branch's own limit (2 g max|F_inf| for a Maxwell cell under a
//!   history reaching max|F_inf|, the slip force of a Jenkins cell, g K x_f
//!   of an x_f cell (K the largest tangent), the saturation of the friction cell);
//! - finiteness: finite inputs give finite outputs;
//! - determinism: the same history gives the same outputs, bit for bit.

use bushing::{
    Backbone, Bushing, Dahl, IwanBank, IwanCellSpec, MaxwellBank, MaxwellForm, MaxwellSpec,
    Polynomial, Real, XfBank, XfForm, XfSpec,
};
use proptest::prelude::*;

type Model<T> =
    Bushing<T, Polynomial<T, 4>, (MaxwellBank<T, 3>, IwanBank<T, 3>, XfBank<T, 1>, Dahl<T>)>;

/// Parameters drawn by proptest.
#[derive(Debug, Clone)]
struct Params {
    form: MaxwellForm,
    /// Corner frequencies (Hz) and fractions of the Maxwell cells.
    maxwell: [(f64, f64); 3],
    /// Slip distances (mm) and fractions of the Jenkins cells.
    jenkins: [(f64, f64); 3],
    /// x_f cell: corner (Hz), fraction, x_f (mm).
    xf: (f64, f64, f64),
    /// Dahl cell: stiffness, friction force, exponent.
    dahl: (f64, f64, f64),
    dt: f64,
}

fn params() -> impl Strategy<Value = Params> {
    let form = prop::sample::select(MaxwellForm::ALL.to_vec());
    // Fractions of at most 0.1 each: seven branches stay below one.
    let cell = (1e-2f64..1e3, 1e-3f64..0.1);
    let slip = (1e-3f64..2.0, 1e-3f64..0.1);
    (
        form,
        [cell.clone(), cell.clone(), cell],
        [slip.clone(), slip.clone(), slip],
        (1e-2f64..1e3, 1e-3f64..0.1, 1e-3f64..1.0),
        (1.0f64..1e4, 0.1f64..50.0, 0.3f64..4.0),
        prop::sample::select(vec![1e-4, 5e-4, 1e-3, 5e-3]),
    )
        .prop_map(|(form, maxwell, jenkins, xf, dahl, dt)| Params {
            form,
            maxwell,
            jenkins,
            xf,
            dahl,
            dt,
        })
}

/// A closed history: from 0 through turning points (mm) and back to 0,
/// each leg in `steps` samples.
fn history() -> impl Strategy<Value = Vec<f64>> {
    (prop::collection::vec(-4.0f64..4.0, 1..8), 1usize..60).prop_map(|(turns, steps)| {
        let mut xs = Vec::new();
        let mut from = 0.0;
        for to in turns.into_iter().chain(std::iter::once(0.0)) {
            for k in 1..=steps {
                xs.push(from + (to - from) * k as f64 / steps as f64);
            }
            from = to;
        }
        xs
    })
}

/// The model, or `None` when the draw breaks a bound (an explicit form at
/// ω·dt >= 1): those are refused by construction, as tested elsewhere, and
/// the draw is replaced.
fn model<T: Real>(p: &Params) -> Option<Model<T>> {
    let maxwell = p.maxwell.map(|(f, g)| MaxwellSpec::hz(f, g));
    let jenkins = p
        .jenkins
        .map(|(x_f, g)| IwanCellSpec::from_slip_distance(g, 150.0, x_f));
    let (f, g, x_f) = p.xf;
    let (k_d, f_f, alpha) = p.dahl;
    let backbone = Polynomial::new(&[0.0, 150.0, 0.0, 4.0], (-6.0, 6.0)).ok()?;
    Bushing::new(
        backbone,
        (
            MaxwellBank::new(p.form, &maxwell, p.dt).ok()?,
            IwanBank::new(&jenkins).ok()?,
            XfBank::new(XfForm::ExactRamp, &[XfSpec::hz(f, g, x_f)], p.dt).ok()?,
            Dahl::new(k_d, f_f, alpha).ok()?,
        ),
    )
    .ok()
}

/// The force bound of `p` along `xs` (see the module comment), N.
fn force_bound(p: &Params, xs: &[f64]) -> f64 {
    let backbone =
        Polynomial::<f64, 4>::new(&[0.0, 150.0, 0.0, 4.0], (-6.0, 6.0)).expect("the same backbone");
    let f_max = xs
        .iter()
        .map(|&x| backbone.eval(x).0.abs())
        .fold(0.0, f64::max);
    let g_maxwell: f64 = p.maxwell.iter().map(|c| c.1).sum();
    let g_all = g_maxwell + p.jenkins.iter().map(|c| c.1).sum::<f64>() + p.xf.1;
    let slip: f64 = p.jenkins.iter().map(|(x_f, g)| g * 150.0 * x_f).sum();
    // The x_f cell saturates at g K x_f with K the backbone's tangent.
    let k_max = xs.iter().map(|&x| backbone.eval(x).1).fold(0.0, f64::max);
    let xf = p.xf.1 * k_max * p.xf.2;
    (1.0 - g_all) * f_max + 2.0 * g_maxwell * f_max + slip + xf + p.dahl.1
}

/// Force, tangent and dissipated energy of every step, as bit patterns.
fn run<T: Real>(b: &Model<T>, xs: &[f64]) -> Vec<[u64; 3]> {
    let mut s = b.state_at(T::ZERO);
    xs.iter()
        .map(|&x| {
            let o = b.step(&mut s, T::from_f64(x));
            [o.force.bits(), o.tangent.bits(), o.dissipated.bits()]
        })
        .collect()
}

fn check<T: Real>(p: &Params, xs: &[f64]) -> Result<(), TestCaseError> {
    let b = model::<T>(p);
    prop_assume!(b.is_some(), "parameters refused by construction");
    let Some(b) = b else {
        return Ok(());
    };
    let bound = force_bound(p, xs);
    let mut s = b.state_at(T::ZERO);
    let mut cycle = 0.0f64;
    for (n, &x) in xs.iter().enumerate() {
        let o = b.step(&mut s, T::from_f64(x));
        let (f, k, d) = (o.force.to_f64(), o.tangent.to_f64(), o.dissipated.to_f64());
        prop_assert!(
            f.is_finite() && k.is_finite() && d.is_finite(),
            "step {n}: non-finite output at x = {x}"
        );
        prop_assert!(d >= 0.0, "step {n}: dissipated {d} < 0");
        // Rounding of the sum in the working type.
        let slack = 1e-4 * bound;
        prop_assert!(
            f.abs() <= bound + slack,
            "step {n}: |F| = {} above the bound {bound}",
            f.abs()
        );
        cycle += d;
    }
    prop_assert!(cycle >= 0.0, "energy over the closed cycle {cycle} < 0");
    prop_assert_eq!(run(&b, xs), run(&b, xs), "two runs differ");
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn passive_bounded_finite_deterministic_f64(p in params(), xs in history()) {
        check::<f64>(&p, &xs)?;
    }

    #[test]
    fn passive_bounded_finite_deterministic_f32(p in params(), xs in history()) {
        check::<f32>(&p, &xs)?;
    }
}
