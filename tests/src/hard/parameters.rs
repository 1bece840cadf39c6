//! Hard cases of parameters at and beyond their bounds: each refused with
//! the right variant, and each bound itself accepted.

use bushing::tracker::{Filter, Measured, ModalTracker, ModeInit, SensorSpec, Tuning};
use bushing::{
    Berg, BoucWen, Dahl, FractionalSpec, Grunwald, IwanBank, IwanCellSpec, MaxwellBank,
    MaxwellForm, MaxwellSpec, MonotoneSpline, Param, ParamError, Polynomial, XfBank, XfForm,
    XfSpec,
};

use super::{Measure, miss, refused_as};

pub(super) fn maxwell_parameters_refused() -> Measure {
    let dt = 1e-3;
    let form = MaxwellForm::RateExactRamp;
    let one = |omega: f64, g: f64, dt: f64| {
        MaxwellBank::<f32, 1>::new(form, &[MaxwellSpec::new(omega, g)], dt)
    };
    let mut wrong = 0.0;
    wrong += refused_as(one(0.0, 0.2, dt), |e| {
        matches!(
            e,
            ParamError::NotPositive {
                param: Param {
                    name: "omega",
                    index: Some(0)
                },
                ..
            }
        )
    });
    wrong += refused_as(one(-1.0, 0.2, dt), |e| {
        matches!(
            e,
            ParamError::NotPositive {
                param: Param { name: "omega", .. },
                ..
            }
        )
    });
    wrong += refused_as(one(f64::NAN, 0.2, dt), |e| {
        matches!(
            e,
            ParamError::NotFinite {
                param: Param { name: "omega", .. }
            }
        )
    });
    wrong += refused_as(one(10.0, 0.0, dt), |e| {
        matches!(
            e,
            ParamError::NotPositive {
                param: Param { name: "g", .. },
                ..
            }
        )
    });
    wrong += refused_as(one(10.0, 1.5, dt), |e| {
        matches!(e, ParamError::CellFractionAboveOne { cell: Some(0), .. })
    });
    wrong += refused_as(one(10.0, 0.2, 0.0), |e| {
        matches!(
            e,
            ParamError::NotPositive {
                param: Param { name: "dt", .. },
                ..
            }
        )
    });
    wrong += refused_as(one(10.0, 0.2, f64::INFINITY), |e| {
        matches!(
            e,
            ParamError::NotFinite {
                param: Param { name: "dt", .. }
            }
        )
    });
    let two = MaxwellBank::<f32, 2>::new(
        form,
        &[MaxwellSpec::new(10.0, 0.6), MaxwellSpec::new(100.0, 0.6)],
        dt,
    );
    wrong += refused_as(two, |e| matches!(e, ParamError::FractionsAboveOne { .. }));
    // At the bounds: g = 1 and a cell at 1e-7 rad/s are accepted.
    wrong += miss(one(10.0, 1.0, dt).is_ok());
    wrong += miss(one(1e-7, 0.5, dt).is_ok());
    Ok(wrong)
}

pub(super) fn hysteresis_parameters_refused() -> Measure {
    let mut wrong = 0.0;
    wrong += refused_as(
        IwanBank::<f32, 1>::new(&[IwanCellSpec::new(0.2, 0.0)]),
        |e| matches!(e, ParamError::NotPositive { .. }),
    );
    wrong += refused_as(
        IwanBank::<f32, 1>::new(&[IwanCellSpec::new(0.2, f64::NAN)]),
        |e| matches!(e, ParamError::NotFinite { .. }),
    );
    wrong += refused_as(
        IwanBank::<f32, 1>::new(&[IwanCellSpec::new(-0.1, 1.0)]),
        |e| matches!(e, ParamError::NotPositive { .. }),
    );
    wrong += refused_as(
        IwanBank::<f32, 2>::new(&[IwanCellSpec::new(0.7, 1.0), IwanCellSpec::new(0.7, 2.0)]),
        |e| matches!(e, ParamError::FractionsAboveOne { .. }),
    );
    wrong += refused_as(
        XfBank::<f32, 1>::new(XfForm::ExactRamp, &[XfSpec::hz(5.0, 0.1, 0.0)], 1e-3),
        |e| matches!(e, ParamError::NotPositive { .. }),
    );
    // α in (0, 1]: 1 is the dashpot, accepted.
    wrong += refused_as(
        Grunwald::<f32, 16>::new(FractionalSpec::hz(2.0, 1.5, 0.5), 1e-3),
        |e| matches!(e, ParamError::OutOfRange { .. }),
    );
    wrong += refused_as(
        Grunwald::<f32, 16>::new(FractionalSpec::hz(2.0, 0.0, 0.5), 1e-3),
        |e| matches!(e, ParamError::NotPositive { .. }),
    );
    wrong += miss(Grunwald::<f32, 16>::new(FractionalSpec::hz(2.0, 1.0, 0.5), 1e-3).is_ok());
    wrong += refused_as(Dahl::<f32>::new(100.0, 0.0, 1.0), |e| {
        matches!(e, ParamError::NotPositive { .. })
    });
    wrong += refused_as(BoucWen::<f32>::new(100.0, 1.0, 30.0, 10.0, 0.0), |e| {
        matches!(
            e,
            ParamError::NotPositive { .. } | ParamError::OutOfRange { .. }
        )
    });
    wrong += refused_as(Berg::<f32>::new(3.0, -0.1), |e| {
        matches!(e, ParamError::NotPositive { .. })
    });
    Ok(wrong)
}

pub(super) fn backbone_parameters_refused() -> Measure {
    let mut wrong = 0.0;
    wrong += refused_as(
        MonotoneSpline::<f32, 8>::new(&[0.0, 1.0, 1.0, 2.0], &[0.0, 1.0, 2.0, 3.0]),
        |e| matches!(e, ParamError::NotIncreasing { .. }),
    );
    wrong += refused_as(
        MonotoneSpline::<f32, 8>::new(&[0.0, 1.0, 2.0, 3.0], &[0.0, 1.0, 0.5, 3.0]),
        |e| matches!(e, ParamError::NotIncreasing { .. }),
    );
    wrong += refused_as(MonotoneSpline::<f32, 8>::new(&[0.0], &[0.0]), |e| {
        matches!(e, ParamError::TooFew { .. })
    });
    wrong += refused_as(
        MonotoneSpline::<f32, 2>::new(&[0.0, 1.0, 2.0], &[0.0, 1.0, 2.0]),
        |e| {
            matches!(
                e,
                ParamError::TooMany {
                    capacity: 2,
                    got: 3,
                    ..
                }
            )
        },
    );
    wrong += refused_as(
        MonotoneSpline::<f32, 8>::new(&[0.0, 1.0, 2.0], &[0.0, 1.0]),
        |e| matches!(e, ParamError::LengthMismatch { .. }),
    );
    // A cubic whose tangent 100 - 3 x² turns negative inside the range.
    wrong += refused_as(
        Polynomial::<f32, 4>::new(&[0.0, 100.0, 0.0, -1.0], (-10.0, 10.0)),
        |e| matches!(e, ParamError::TangentNotPositive { .. }),
    );
    wrong += refused_as(Polynomial::<f32, 2>::new(&[0.0, 100.0], (1.0, 1.0)), |e| {
        matches!(e, ParamError::EmptyRange { .. })
    });
    Ok(wrong)
}

pub(super) fn tracker_parameters_refused() -> Measure {
    let sensor = [SensorSpec {
        measured: Measured::Acceleration,
        noise: 0.01,
    }];
    let mode = |frequency: f64| {
        [ModeInit {
            frequency,
            damping: 0.01,
        }]
    };
    let tuning = Tuning::default();
    let dt = 1e-3;
    let mut wrong = 0.0;
    for f in [500.0, 600.0, 0.0, -20.0, f64::NAN] {
        let r =
            ModalTracker::<f32, 4>::new(dt, &sensor, &mode(f), &[(1.0, 0.0)], &tuning, Filter::Ekf);
        wrong += miss(r.is_err());
    }
    let silent = [SensorSpec {
        measured: Measured::Acceleration,
        noise: 0.0,
    }];
    wrong += miss(
        ModalTracker::<f32, 4>::new(
            dt,
            &silent,
            &mode(20.0),
            &[(1.0, 0.0)],
            &tuning,
            Filter::Ekf,
        )
        .is_err(),
    );
    wrong += miss(
        ModalTracker::<f32, 4>::new(dt, &sensor, &mode(20.0), &[], &tuning, Filter::Ekf).is_err(),
    );
    // Two sensors and one mode need 6 states, not 4.
    let two = [sensor[0], sensor[0]];
    wrong += miss(
        ModalTracker::<f32, 4>::new(
            dt,
            &two,
            &mode(20.0),
            &[(1.0, 0.0), (1.0, 0.0)],
            &tuning,
            Filter::Ekf,
        )
        .is_err(),
    );
    Ok(wrong)
}
