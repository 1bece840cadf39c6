//! Hard cases of the outputs a step returns: effect forces beyond the
//! guard, tables that do not fit the working type, the energy of the step
//! that closes an inner loop, no negative energy on any step, and the 6-DOF
//! tangent after a refused pose.

use bushing::six_dof::{Connectivity, Pose, Quat, SixDof};
use bushing::{
    Bushing, Dashpot, Effect, EffectOutput, Faults, FirstLoading, IwanBank, IwanCellSpec, KfTable,
    MaxwellBank, MaxwellForm, Param, ParamError, Polynomial, Real, TurningPoints, XfBank, XfForm,
    XfSpec,
};

use super::maxwell::four_cells;
use super::{Measure, miss, refused_as, worst};
use crate::check::param;
use crate::stack::sts_bushing;
use bushing_kernels::Noise;

/// A K_f table in f32 whose values, force gained, slope or dissipated work
/// leave the working type is refused, naming the point; one that fits is
/// accepted.
pub(super) fn kf_table_beyond_working_type_refused() -> Measure {
    let out_of_range = |name: &'static str, index: usize| move |e: &ParamError| matches!(e, ParamError::OutOfRange { param, .. } if *param == Param::item(name, index));
    let table = |d: &[f64], k: &[f64]| KfTable::<f32, 4>::new(d, k);
    let mut wrong = 0.0;
    // K beyond f32 (the force was NaN), and beyond the guard (9e18 N).
    wrong += refused_as(table(&[0.0, 1.0], &[1e39, 0.0]), out_of_range("k", 0));
    wrong += refused_as(table(&[0.0, 1.0], &[1e20, 0.0]), out_of_range("k", 0));
    // A distance beyond the guard, a slope 1e31 N/mm², a work 4e25 mJ.
    wrong += refused_as(table(&[0.0, 1e19], &[1.0, 1.0]), out_of_range("d", 1));
    wrong += refused_as(
        table(&[0.0, 1e-30], &[10.0, 0.0]),
        out_of_range("k slope", 0),
    );
    wrong += refused_as(table(&[0.0, 1e9], &[1e9, 5e8]), out_of_range("W(d)", 1));
    wrong += miss(table(&[0.0, 0.1, 1.0], &[300.0, 100.0, 0.0]).is_ok());
    Ok(wrong)
}

/// Steps a bushing to each `x`: `true` where the step must be refused for
/// a force beyond the guard (state kept, last force returned, flag
/// raised), `false` where it must be accepted with a finite force and
/// tangent within the guard. Returns the wrong verdicts.
fn guard_verdicts<B, E>(b: &Bushing<f32, B, (E,)>, path: &[(f32, bool)]) -> f64
where
    B: bushing::Backbone<f32>,
    E: Effect<f32, Report = EffectOutput<f32>>,
{
    let mut s = b.state_at(0.0);
    let mut wrong = 0.0;
    for &(x, refuse) in path {
        let before = s.clone();
        let out = b.step(&mut s, x);
        if refuse {
            wrong += miss(out.effects.is_none() && out.force == before.force());
            wrong += miss(s.effects() == before.effects() && s.x() == before.x());
            wrong += miss(s.faults().contains(Faults::FORCE_OUT_OF_RANGE));
        } else {
            let guarded = |v: f32| v.abs() <= <f32 as Real>::GUARD;
            wrong += miss(out.effects.is_some() && guarded(out.force) && guarded(out.tangent));
            wrong += miss(s.faults().is_empty());
        }
        s.clear_faults();
    }
    wrong
}

/// Effects driven far beyond their data: a constant K_f of 1e15 N/mm at
/// 2 m (2e18 N), a dashpot at 1e19 N, a tangent of 1.5e18 N/mm summed from
/// a backbone and a table each within the guard, and a table whose force
/// is within the guard but whose total with the backbone is not. Each
/// such step is refused and the next ordinary one accepted.
pub(super) fn effect_forces_beyond_guard_refused() -> Measure {
    let soft = || Polynomial::<f32, 2>::linear(1.0).map_err(param);
    let table = |k: f64| {
        KfTable::<f32, 1>::new(&[0.0], &[k])
            .map(|t| TurningPoints::<_, 8>::new(t, FirstLoading::Masing))
            .map_err(param)
    };
    let stiff = Bushing::new(soft()?, (table(1e15)?,)).map_err(param)?;
    let mut wrong = guard_verdicts(&stiff, &[(1.0, false), (2000.0, true), (1.5, false)]);
    // Backbone and table tangents each within the guard, their sum not.
    let rigid = Polynomial::<f32, 2>::linear(1e18).map_err(param)?;
    let rigid = Bushing::new(rigid, (table(5e17)?,)).map_err(param)?;
    wrong += guard_verdicts(&rigid, &[(1e-6, true), (-1e-6, true)]);
    let dashpot = Dashpot::<f32>::new(1e6, 1e-6).map_err(param)?;
    let dashpot = Bushing::new(soft()?, (dashpot,)).map_err(param)?;
    wrong += guard_verdicts(&dashpot, &[(1e3, false), (1e7, true), (1e3 + 1.0, false)]);
    // The effect's own force, 2e17 N, is within the guard; with the
    // backbone's 1e18 N the total is not.
    let total = Bushing::new(soft()?, (table(0.2)?,)).map_err(param)?;
    wrong += guard_verdicts(&total, &[(1e17, false), (1e18, true), (5e17, false)]);
    Ok(wrong)
}

/// The STS law (C = 400 N²/mm, K_1 = 300 N/mm) and an Iwan bank taken to
/// ±1 mm, then cycled between 0.2 and 0.4 mm at 10 steps per branch: the
/// energy of the second inner loop against Masing's loop area (for STS
/// H(Δ)³ / (6C), Δ = 0.2 mm; for the bank Σ 4 F_f (Δ/2 - x_f) over the cells
/// that slip). The step that closes the loop used to be integrated on the
/// outer branch (+8.2 %).
pub(super) fn inner_loop_energy_at_ten_steps() -> Measure {
    let (c, k1, lo, hi, n) = (400.0, 300.0, 0.2, 0.4, 10);
    let sts = sts_bushing::<16>()?;
    let a = c / k1;
    let h = libm::sqrt(2.0 * c * (hi - lo) + a * a) - a;
    let sts_error = inner_loop_energy(&sts, lo, hi, n) / (h * h * h / (6.0 * c)) - 1.0;
    let k = 100.0;
    let slips = [0.01, 0.03, 0.06, 0.09, 0.15];
    let cells = slips.map(|x_f| IwanCellSpec::from_slip_distance(0.15, k, x_f));
    let iwan = IwanBank::<f32, 5>::new(&cells).map_err(param)?;
    let bb = Polynomial::<f32, 2>::linear(k).map_err(param)?;
    let iwan = Bushing::new(bb, (iwan,)).map_err(param)?;
    let area: f64 = slips
        .iter()
        .map(|&x_f| 4.0 * 0.15 * k * x_f * (0.5 * (hi - lo) - x_f).max(0.0))
        .sum();
    let iwan_error = inner_loop_energy(&iwan, lo, hi, n) / area - 1.0;
    Ok(worst(libm::fabs(sts_error), libm::fabs(iwan_error)))
}

/// Energy of the second loop hi -> lo -> hi, `n` steps per branch, after
/// 0 -> 1 -> -1 -> hi in steps of 0.01 mm.
fn inner_loop_energy<B, E>(b: &Bushing<f32, B, (E,)>, lo: f64, hi: f64, n: usize) -> f64
where
    B: bushing::Backbone<f32>,
    E: Effect<f32, Report = EffectOutput<f32>>,
{
    let mut s = b.state_at(0.0);
    let mut x = 0.0f64;
    for target in [1.0, -1.0, hi] {
        let steps = (libm::fabs(target - x) / 0.01) as usize;
        for k in 1..=steps {
            b.step(&mut s, (x + (target - x) * k as f64 / steps as f64) as f32);
        }
        x = target;
    }
    let mut energy = 0.0;
    for cycle in 0..2 {
        for k in 1..=2 * n {
            let u = if k <= n { k } else { 2 * n - k } as f64 / n as f64;
            let out = b.step(&mut s, (hi - (hi - lo) * u) as f32);
            if cycle == 1 {
                energy += out.dissipated as f64;
            }
        }
    }
    energy
}

/// A 6-DOF bushing (six hardening axes, offsets on both nodes) in both
/// connectivities: after a refused pose (NaN orientation, NaN or huge
/// position, a quaternion that is not a rotation) the tangent at that pose
/// is `None`, and the tangent at the last accepted pose is finite.
pub(super) fn six_dof_tangent_after_refused_pose() -> Measure {
    let axis = || {
        let bb = Polynomial::<f32, 4>::new(&[0.0, 150.0, 0.0, 4.0], (-6.0, 6.0)).map_err(param)?;
        Bushing::new(bb, ()).map_err(param)
    };
    let axes = [axis()?, axis()?, axis()?, axis()?, axis()?, axis()?];
    let pose = |p: [f32; 3], r: [f64; 3]| Pose {
        position: p,
        orientation: Quat::<f32>::from_rotation_vector(r),
    };
    let node1 = pose([0.0; 3], [0.0; 3]);
    let good = pose([0.3, -0.2, 0.1], [0.2, -0.1, 0.4]);
    let mut bad = [good; 4];
    bad[0].orientation.w = f32::NAN;
    bad[1].position[1] = f32::NAN;
    bad[2].position[0] = 1e30;
    bad[3].orientation.w = 2.0;
    let finite =
        |t: Option<[[f32; 12]; 12]>| t.is_some_and(|m| m.iter().flatten().all(|v| v.is_finite()));
    let mut wrong = 0.0;
    for connectivity in [Connectivity::Attached, Connectivity::Invariant] {
        let offsets = [[0.01, 0.02, -0.01], [-0.02, 0.0, 0.03]];
        let b = SixDof::new(axes.clone(), offsets, connectivity).map_err(param)?;
        let mut s = b.state_at(&node1, &node1);
        let accepted = b.step(&mut s, &node1, &good);
        wrong += miss(finite(b.tangent(&accepted, &node1, &good)));
        for pose in &bad {
            let out = b.step(&mut s, &node1, pose);
            wrong += miss(!s.faults().is_empty() && out.loads == accepted.loads);
            wrong += miss(b.tangent(&out, &node1, pose).is_none());
            wrong += miss(finite(b.tangent(&out, &node1, &good)));
            s.clear_faults();
        }
    }
    Ok(wrong)
}

/// The default-like bushing (4 Maxwell, 3 Jenkins, 1 x_f) under random
/// closed cycles: no step dissipates a negative energy.
pub(super) fn dissipation_never_negative() -> Measure {
    let dt = 5e-4;
    let maxwell =
        MaxwellBank::<f32, 4>::new(MaxwellForm::RateExactRamp, &four_cells(), dt).map_err(param)?;
    let jenkins = [
        IwanCellSpec::from_slip_distance(0.05, 150.0, 0.05),
        IwanCellSpec::from_slip_distance(0.05, 150.0, 0.2),
        IwanCellSpec::from_slip_distance(0.05, 150.0, 0.8),
    ];
    let iwan = IwanBank::<f32, 3>::new(&jenkins).map_err(param)?;
    let xf = XfBank::<f32, 1>::new(XfForm::ExactRamp, &[XfSpec::hz(5.0, 0.05, 0.02)], dt)
        .map_err(param)?;
    let bb = Polynomial::<f32, 4>::new(&[0.0, 150.0, 0.0, 4.0], (-6.0, 6.0)).map_err(param)?;
    let b = Bushing::new(bb, (maxwell, iwan, xf)).map_err(param)?;
    let mut s = b.state_at(0.0);
    let mut rng = Noise::new(17);
    let mut negative = 0.0;
    // Closed triangular cycles of random amplitude (1e-4 to 3 mm) and
    // length (4 to 400 steps), around random offsets.
    for _ in 0..200 {
        let amplitude = libm::pow(10.0, -4.0 + 4.5 * rng.uniform()).min(3.0);
        let offset = 2.0 * (rng.uniform() - 0.5);
        let half = 2 + (rng.uniform() * 200.0) as usize;
        for k in 0..2 * half {
            let u = if k < half {
                k as f64 / half as f64
            } else {
                (2 * half - k) as f64 / half as f64
            };
            let out = b.step(&mut s, (offset + amplitude * u) as f32);
            negative += miss(out.dissipated >= 0.0);
        }
    }
    Ok(negative)
}
