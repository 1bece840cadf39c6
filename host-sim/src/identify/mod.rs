//! Identification of a bushing model from a measured test campaign (seed
//! 000 chapter 3): the campaign as recorded ([`campaign`]) and the
//! pre-processing of its tests ([`sine`]: the first harmonic of each
//! sine; [`relax`]: the relaxation of each multi-step hold; [`triangle`]:
//! the filtered branches of each triangle test and their instantaneous
//! modulus; [`report`]: all of it in a report with its figures), the
//! first stage of the identification ([`backbone`]: the long-term
//! backbone from the triangles' midlines), the second ([`hysteresis`]:
//! Jenkins cells placed on the normalised instantaneous-modulus curve),
//! the third ([`stages`]: Maxwell cells; [`xf_stage`]: x_f cells on the
//! sines' harmonics), the joint refinement ([`joint`]) on replays of the
//! records ([`replay`]), and campaigns generated from a known model
//! ([`synth`]).

pub mod backbone;
pub mod campaign;
pub mod class;
pub mod export;
pub mod hysteresis;
pub mod joint;
pub mod outcome;
pub mod relax;
pub mod replay;
pub mod report;
pub mod sine;
pub mod stages;
pub mod summary;
pub mod synth;
pub mod triangle;
pub mod xf_stage;

/// The smallest and largest of `values` (`(inf, -inf)` when there are
/// none).
pub fn extremes<'a>(values: impl IntoIterator<Item = &'a f64>) -> (f64, f64) {
    values
        .into_iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        })
}
