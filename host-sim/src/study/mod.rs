//! The studies built on the engines: the work-precision report ([`precision`]), the stress
//! cases on stiff and extreme devices ([`stress`]), the frequency sweep ([`sweep`]).

pub mod precision;
pub mod stress;
pub mod sweep;
