//! Identification of a bushing model from a measured test campaign (seed
//! 000 chapter 3): the campaign as recorded ([`campaign`]) and the
//! pre-processing of its tests ([`sine`]: the first harmonic of each
//! sine).

pub mod campaign;
pub mod sine;
