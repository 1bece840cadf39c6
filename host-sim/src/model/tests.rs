use super::*;
use bushing::fractional::FractionalSpec;

use crate::scene::FRACTIONAL_TAPS;

#[test]
fn the_fractional_menu_builds_every_listed_length_and_no_other() {
    let spec = FractionalSpec::hz(5.0, 0.5, 0.6);
    for n in 0..=2 * FRACTIONAL_TAPS[FRACTIONAL_TAPS.len() - 1] {
        match DynGrunwald::<f32>::new(spec, n, 1e-3) {
            Ok(cell) => {
                assert!(FRACTIONAL_TAPS.contains(&n), "{n} is not listed");
                assert_eq!(cell.taps(), n);
                assert_eq!(cell.fraction(), 0.6);
                assert_eq!(cell.dt(), Some(1e-3));
            }
            Err(e) => {
                assert!(!FRACTIONAL_TAPS.contains(&n), "{n}: {e}");
                assert!(matches!(e, ParamError::OutOfRange { .. }), "{e}");
            }
        }
    }
}

#[test]
fn a_fractional_state_is_copied_into_its_own_box() {
    let cell = DynGrunwald::<f64>::new(FractionalSpec::hz(5.0, 0.5, 0.6), 256, 1e-3).unwrap();
    let drive = Drive {
        x: 1.0,
        dx: 1.0,
        f_inf: 100.0,
        df_inf: 100.0,
        k_inf: 100.0,
    };
    let mut stepped = cell.rest(0.0);
    cell.step(&mut stepped, &drive);
    let mut copy = cell.rest(0.0);
    let DynGrunwaldState::X256(boxed) = &copy else {
        panic!("256 taps");
    };
    let before = std::ptr::from_ref(&**boxed);
    copy.clone_from(&stepped);
    assert_eq!(copy, stepped);
    let DynGrunwaldState::X256(boxed) = &copy else {
        panic!("256 taps");
    };
    assert_eq!(std::ptr::from_ref(&**boxed), before, "no new allocation");
}
