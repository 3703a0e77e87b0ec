//! The studies built on the engines: the work-precision study behind `report`
//! ([`work_precision`]), the stiff and extreme cases behind `stress` ([`stiff_cases`]), the
//! frequency response behind `sweep` ([`frequency_response`]).

pub mod frequency_response;
pub mod stiff_cases;
pub mod work_precision;
