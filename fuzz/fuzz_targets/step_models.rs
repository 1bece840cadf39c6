//! Every model of the core built from arbitrary parameters (any f64 bit
//! pattern: NaN, infinities, subnormals, huge values) and, when
//! construction succeeds, stepped in f32 over arbitrary inputs (any f32 bit
//! pattern). Construction must end in a model or a typed error; a step
//! must never panic; a refused input (non-finite, or beyond the backbone's
//! guard) must leave the force unchanged; an accepted one must give a
//! finite force, tangent and dissipated energy. The 6-DOF bushing is driven
//! by arbitrary node poses: a refused configuration holds its loads, an
//! accepted one gives finite loads.
#![no_main]

use arbitrary::{Result, Unstructured};
use bushing::six_dof::{Connectivity, Pose, Quat, SixDof};
use bushing::tracker::{Filter, Measured, ModalTracker, ModeInit, SensorSpec, Tuning, UtParams};
use bushing::{
    Backbone, Berg, BoucWen, Bushing, Dahl, Dashpot, Effect, FirstLoading, FractionalSpec,
    Grunwald, IwanBank, IwanCellSpec, IwanSliders, MaxwellBank, MaxwellForm, MaxwellSpec,
    MonotoneSpline, Polynomial, Sts, TurningPoints, XfBank, XfForm, XfSpec,
};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let _ = one_model(&mut u);
});

/// A parameter: mostly in a plausible range, sometimes any bit pattern.
fn param(u: &mut Unstructured<'_>, lo: f64, hi: f64) -> Result<f64> {
    Ok(match u.int_in_range(0u8..=7)? {
        0 => f64::from_bits(u.arbitrary()?),
        1 => [0.0, -0.0, f64::NAN, f64::INFINITY, -1.0, 1e308, 1e-308][u.choose_index(7)?],
        _ => lo + (hi - lo) * (u.int_in_range(0u32..=1 << 20)? as f64 / (1 << 20) as f64),
    })
}

/// An input displacement: mostly within ±10 mm, sometimes any bit pattern.
fn input(u: &mut Unstructured<'_>) -> Result<f32> {
    Ok(match u.int_in_range(0u8..=15)? {
        0 => f32::from_bits(u.arbitrary()?),
        1 => [f32::NAN, f32::INFINITY, -f32::INFINITY, 1e30, -1e30, 0.0][u.choose_index(6)?],
        _ => (u.int_in_range(-10_000i32..=10_000)? as f32) * 1e-3,
    })
}

fn one_model(u: &mut Unstructured<'_>) -> Result<()> {
    let dt = param(u, 1e-5, 1e-2)?;
    let backbone = match Polynomial::<f32, 4>::new(
        &[
            0.0,
            param(u, 1.0, 1e3)?,
            param(u, -10.0, 10.0)?,
            param(u, 0.0, 10.0)?,
        ],
        (param(u, -20.0, -1.0)?, param(u, 1.0, 20.0)?),
    ) {
        Ok(b) => b,
        Err(_) => Polynomial::<f32, 4>::new(&[0.0, 150.0, 0.0, 4.0], (-6.0, 6.0))
            .expect("the fallback backbone"),
    };
    match u.int_in_range(0u8..=13)? {
        0 => {
            let form = MaxwellForm::ALL[u.choose_index(MaxwellForm::ALL.len())?];
            let cells = [
                MaxwellSpec::new(param(u, 1e-3, 1e4)?, param(u, 0.0, 0.5)?),
                MaxwellSpec::new(param(u, 1e-3, 1e4)?, param(u, 0.0, 0.5)?),
            ];
            if let Ok(bank) = MaxwellBank::<f32, 2>::new(form, &cells, dt) {
                drive(u, backbone, bank)?;
            }
        }
        1 => {
            let cells = [
                IwanCellSpec::new(param(u, 0.0, 0.5)?, param(u, 0.0, 100.0)?),
                IwanCellSpec::new(param(u, 0.0, 0.5)?, param(u, 0.0, 100.0)?),
            ];
            if let Ok(bank) = IwanBank::<f32, 2>::new(&cells) {
                drive(u, backbone, bank)?;
            }
            if let Ok(bank) = IwanSliders::<f32, 2>::new(&cells, param(u, 1.0, 1e3)?) {
                drive(u, backbone, bank)?;
            }
        }
        2 => {
            let form = XfForm::ALL[u.choose_index(XfForm::ALL.len())?];
            let spec = XfSpec {
                omega: param(u, 0.0, 1e3)?,
                g: param(u, 0.0, 0.5)?,
                x_f: param(u, 1e-4, 1.0)?,
            };
            if let Ok(bank) = XfBank::<f32, 1>::new(form, &[spec], dt) {
                drive(u, backbone, bank)?;
            }
        }
        3 => {
            let spec = FractionalSpec::new(
                param(u, 0.1, 1e3)?,
                param(u, 0.0, 1.0)?,
                param(u, 0.0, 0.9)?,
            );
            if let Ok(cell) = Grunwald::<f32, 16>::new(spec, dt) {
                drive(u, backbone, cell)?;
            }
        }
        4 => {
            if let Ok(d) = Dahl::<f32>::new(
                param(u, 1.0, 1e4)?,
                param(u, 0.0, 50.0)?,
                param(u, 0.0, 5.0)?,
            ) {
                drive(u, backbone, d)?;
            }
        }
        5 => {
            if let Ok(bw) = BoucWen::<f32>::new(
                param(u, 1.0, 1e3)?,
                param(u, 0.0, 2.0)?,
                param(u, 0.0, 50.0)?,
                param(u, -50.0, 50.0)?,
                param(u, 0.0, 60.0)?,
            ) {
                drive(u, backbone, bw)?;
            }
        }
        6 => {
            if let Ok(b) = Berg::<f32>::new(param(u, 0.0, 50.0)?, param(u, 0.0, 1.0)?) {
                drive(u, backbone, b)?;
            }
        }
        7 => {
            if let Ok(law) = Sts::<f32>::new(param(u, 0.0, 1e3)?, param(u, 0.0, 1e3)?) {
                let first = if u.arbitrary()? {
                    FirstLoading::Masing
                } else {
                    FirstLoading::Ignored
                };
                drive(u, backbone, TurningPoints::<_, 8>::new(law, first))?;
            }
        }
        8 => {
            let n = u.int_in_range(2usize..=6)?;
            let mut xs = [0.0; 6];
            let mut fs = [0.0; 6];
            for (x, f) in xs.iter_mut().zip(fs.iter_mut()) {
                *x = param(u, -10.0, 10.0)?;
                *f = param(u, -1e3, 1e3)?;
            }
            if let Ok(spline) = MonotoneSpline::<f32, 6>::new(&xs[..n], &fs[..n]) {
                drive(u, spline, ())?;
            }
        }
        9 => {
            let form = MaxwellForm::ALL[u.choose_index(MaxwellForm::ALL.len())?];
            let mut bank = match MaxwellBank::<f32, 2>::new(
                form,
                &[MaxwellSpec::hz(1.0, 0.2), MaxwellSpec::hz(50.0, 0.2)],
                1e-3,
            ) {
                Ok(b) => b,
                Err(_) => return Ok(()),
            };
            let a_t = f32::from_bits(u.arbitrary()?);
            let before = bank.clone();
            if bank.retune::<bushing::LibmExp>(a_t).is_err() {
                assert!(bank == before, "a refused re-tune changed the bank");
            }
            drive(u, backbone, bank)?;
        }
        10 => {
            if let Ok(d) = Dashpot::<f32>::new(param(u, 1e-6, 1e3)?, dt) {
                drive(u, backbone, d)?;
            }
        }
        11 => six_dof(u)?,
        _ => tracker(u, dt)?,
    }
    Ok(())
}

/// A node pose: mostly plausible, sometimes any bit pattern.
fn pose(u: &mut Unstructured<'_>) -> Result<Pose<f32>> {
    let mut r = [0.0; 3];
    let mut p = [0.0f32; 3];
    for (ri, pi) in r.iter_mut().zip(p.iter_mut()) {
        *ri = param(u, -3.0, 3.0)?;
        *pi = input(u)?;
    }
    let mut orientation = Quat::from_rotation_vector(r);
    if u.ratio(1u8, 16)? {
        orientation.w = f32::from_bits(u.arbitrary()?);
    }
    Ok(Pose {
        position: p,
        orientation,
    })
}

/// A 6-DOF bushing of six arbitrary linear laws and offsets, in either
/// connectivity, between two arbitrary moving nodes: a refused
/// configuration holds the loads; an accepted one gives finite loads.
fn six_dof(u: &mut Unstructured<'_>) -> Result<()> {
    let mut laws = Vec::new();
    for _ in 0..6 {
        match Polynomial::<f32, 2>::linear(param(u, 1e-3, 1e6)?).and_then(|p| Bushing::new(p, ())) {
            Ok(b) => laws.push(b),
            Err(_) => return Ok(()),
        }
    }
    let Ok(axes) = <[_; 6]>::try_from(laws) else {
        return Ok(());
    };
    let mut offsets = [[0.0; 3]; 2];
    for o in offsets.iter_mut().flatten() {
        *o = param(u, -100.0, 100.0)?;
    }
    let connectivity = if u.arbitrary()? {
        Connectivity::Invariant
    } else {
        Connectivity::Attached
    };
    let Ok(b) = SixDof::new(axes, offsets, connectivity) else {
        return Ok(());
    };
    let (n1, n2) = (pose(u)?, pose(u)?);
    let mut s = b.state_at(&n1, &n2);
    for _ in 0..u.int_in_range(1usize..=64)? {
        let (n1, n2) = (pose(u)?, pose(u)?);
        let before = s.loads();
        let faults = s.faults();
        let out = b.step(&mut s, &n1, &n2);
        if s.faults() != faults {
            assert!(
                out.loads == before,
                "a refused configuration changed the loads"
            );
        }
        let sum = |f: &[[f32; 3]; 2]| f.iter().flatten().all(|x| x.is_finite());
        assert!(
            sum(&out.loads.force) && sum(&out.loads.moment),
            "non-finite loads"
        );
    }
    Ok(())
}

/// Steps a bushing of `backbone` and `effect` over arbitrary inputs.
fn drive<B: Backbone<f32>, E: Effect<f32>>(
    u: &mut Unstructured<'_>,
    backbone: B,
    effect: E,
) -> Result<()> {
    let Ok(b) = Bushing::new(backbone, (effect,)) else {
        return Ok(());
    };
    let mut s = b.state_at(0.0);
    for _ in 0..u.int_in_range(1usize..=256)? {
        let x = input(u)?;
        let before = s.force();
        let out = b.step(&mut s, x);
        match out.effects {
            None => assert!(
                out.force.to_bits() == before.to_bits(),
                "a refused input changed the force"
            ),
            Some(_) => assert!(
                out.force.is_finite() && out.tangent.is_finite() && out.dissipated.is_finite(),
                "non-finite output for an accepted input {x}"
            ),
        }
    }
    Ok(())
}

/// The modal tracker from arbitrary set-up and samples: no panic, and a
/// state that stays finite.
fn tracker(u: &mut Unstructured<'_>, dt: f64) -> Result<()> {
    let measured = [
        Measured::Displacement,
        Measured::Velocity,
        Measured::Acceleration,
    ][u.choose_index(3)?];
    let sensors = [SensorSpec {
        measured,
        noise: param(u, 1e-4, 1.0)?,
    }];
    let modes = [ModeInit {
        frequency: param(u, 0.1, 400.0)?,
        damping: param(u, 0.0, 0.2)?,
    }];
    let amplitude = (param(u, -10.0, 10.0)?, param(u, -10.0, 10.0)?);
    let filter = if u.arbitrary()? {
        Filter::Ekf
    } else {
        Filter::Ukf(UtParams::default())
    };
    let Ok(t) = ModalTracker::<f32, 4>::new(
        dt,
        &sensors,
        &modes,
        &[amplitude],
        &Tuning::default(),
        filter,
    ) else {
        return Ok(());
    };
    let mut s = t.start();
    for _ in 0..u.int_in_range(1usize..=512)? {
        let y = input(u)?;
        t.step(&mut s, &[y]);
        assert!(
            s.x().iter().all(|v| v.is_finite()),
            "non-finite tracker state"
        );
    }
    Ok(())
}
