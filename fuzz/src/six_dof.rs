//! The 6-DOF bushing: six non-linear laws (a cubic or a spline, with a
//! Maxwell and an Iwan bank each present or not), arbitrary offsets, both
//! connectivities, between two arbitrary moving nodes.
//!
//! Contract: a refused configuration keeps the loads and every axis's
//! state, and has no tangent; an accepted one gives finite loads, axis
//! loads, axis tangents and dissipated energy; a tangent given never holds
//! a non-finite entry.

use arbitrary::{Result, Unstructured};
use bushing::six_dof::{Connectivity, Loads, Pose, Quat, SixDof};
use bushing::{Bushing, IwanBank, IwanCellSpec, MaxwellBank, MaxwellForm};

use crate::contract::built;
use crate::draw::{AnyBackbone, Path, backbone, decades, fallback, fraction, param, time_step};
use crate::maxwell::specs;
use crate::num::Num;

type Law<T> = Bushing<T, AnyBackbone<T>, (Option<MaxwellBank<T, 2>>, Option<IwanBank<T, 2>>)>;

/// One axis: a cubic or spline backbone with a Maxwell and an Iwan bank,
/// each present or not; the plain cubic when the drawn law is refused.
fn law<T: Num>(u: &mut Unstructured<'_>, dt: f64) -> Result<Law<T>> {
    let backbone = backbone(u)?;
    let maxwell = if u.arbitrary()? {
        let form = *u.choose(&MaxwellForm::ALL)?;
        built(MaxwellBank::new(form, &specs::<2>(u)?, dt))
    } else {
        None
    };
    let iwan = if u.arbitrary()? {
        let cells = [
            IwanCellSpec::new(fraction(u, 2)?, decades(u, 1e-2, 1e2)?),
            IwanCellSpec::new(fraction(u, 2)?, decades(u, 1e-2, 1e2)?),
        ];
        built(IwanBank::new(&cells))
    } else {
        None
    };
    Ok(
        built(Bushing::new(backbone, (maxwell, iwan))).unwrap_or_else(|| {
            Bushing::new(AnyBackbone::Polynomial(fallback()), (None, None))
                .expect("the fallback law")
        }),
    )
}

/// A node pose: mostly a rotation, sometimes not a unit quaternion.
fn pose<T: Num>(u: &mut Unstructured<'_>, path: &mut Path<T>) -> Result<Pose<T>> {
    let mut r = [0.0; 3];
    for ri in &mut r {
        *ri = param(u, -3.0, 3.0)?;
    }
    let mut orientation = match u.int_in_range(0u8..=15)? {
        0 => Quat::identity(),
        _ => Quat::from_rotation_vector(r),
    };
    if u.ratio(1u8, 16)? {
        orientation.w = T::any(u)?;
    }
    Ok(Pose {
        position: [path.next(u)?, path.next(u)?, path.next(u)?],
        orientation,
    })
}

fn bits<T: Num>(l: &Loads<T>) -> Vec<u64> {
    l.force
        .iter()
        .chain(&l.moment)
        .flatten()
        .map(|v| v.bits())
        .collect()
}

pub fn fuzz<T: Num>(u: &mut Unstructured<'_>) -> Result<()> {
    let dt = time_step(u)?;
    let axes = [
        law::<T>(u, dt)?,
        law::<T>(u, dt)?,
        law::<T>(u, dt)?,
        law::<T>(u, dt)?,
        law::<T>(u, dt)?,
        law::<T>(u, dt)?,
    ];
    let mut offsets = [[0.0; 3]; 2];
    for o in offsets.iter_mut().flatten() {
        *o = param(u, -100.0, 100.0)?;
    }
    let connectivity = if u.arbitrary()? {
        Connectivity::Invariant
    } else {
        Connectivity::Attached
    };
    let Some(b) = built(SixDof::new(axes, offsets, connectivity)) else {
        return Ok(());
    };
    let _ = (b.connectivity(), b.axis(5).map(Bushing::g0));
    let mut path = Path::new(10.0);
    let mut s = b.state_at(&pose(u, &mut path)?, &pose(u, &mut path)?);
    for _ in 0..u.int_in_range(1usize..=64)? {
        let (n1, n2) = (pose(u, &mut path)?, pose(u, &mut path)?);
        s.clear_faults();
        let before = s.clone();
        let out = if u.ratio(1u8, 16)? {
            let (out, next) = b.trial(&s, &n1, &n2);
            s = next;
            out
        } else {
            b.step(&mut s, &n1, &n2)
        };
        let tangent = b.tangent(&out, &n1, &n2);
        if !s.faults().is_empty() {
            assert!(
                bits(&out.loads) == bits(&before.loads())
                    && bits(&s.loads()) == bits(&before.loads()),
                "a refused configuration changed the loads"
            );
            for k in 0..6 {
                assert_eq!(
                    format!("{:?}", s.axis(k)),
                    format!("{:?}", before.axis(k)),
                    "a refused configuration changed axis {k}"
                );
            }
            assert!(tangent.is_none(), "a refused configuration has a tangent");
        } else {
            let finite = |v: &[T]| v.iter().all(|x| x.is_finite());
            assert!(
                finite(out.loads.force.as_flattened())
                    && finite(out.loads.moment.as_flattened())
                    && finite(&out.local)
                    && finite(&out.tangent)
                    && out.dissipated.is_finite(),
                "an accepted configuration out of the contract: {out:?}"
            );
        }
        if let Some(k) = tangent {
            assert!(
                k.iter().flatten().all(|v| v.is_finite()),
                "a tangent with a non-finite entry"
            );
        }
    }
    Ok(())
}
