//! The model of model.md §§1–7, in one place: the device's parameters and scales
//! (`device`), the material (`material`), the loading branch and small oscillation
//! (`statics`), the equation of motion and its fixed-step integrators (`motion`, §4), the
//! safe region (`safety`), a drive's swing against it (`swing`, §7), and the failure modes
//! they name (`failure`, a leaf).

pub mod device;
pub mod failure;
pub mod guaranteed;
pub mod material;
pub mod motion;
pub mod safety;
pub mod statics;
pub mod swing;
pub mod tolerance;
