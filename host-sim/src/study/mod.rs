//! The studies built on the engines: the work-precision study behind `report`
//! ([`work_precision`]), the stiff and extreme cases behind `stress` ([`stiff_cases`]), the
//! frequency response behind `sweep` ([`frequency_response`]); the driven membrane's
//! nonlinear dynamics: Poincaré sections and bifurcation diagrams ([`stroboscopic`]) and the
//! largest Lyapunov exponent ([`lyapunov`]); the safe drive map beside the board's own
//! acceptance ([`drive_map`]).

pub mod drive_map;
pub mod frequency_response;
pub mod lyapunov;
pub mod stiff_cases;
pub mod stroboscopic;
pub mod work_precision;
