//! The model of model.md §§1–6, in one place: the device's parameters and scales
//! (`device`), the material (`material`), the loading branch and small oscillation
//! (`statics`), the safe region (`safety`), a drive's swing against it (`swing`, §7), and the failure modes they name (`failure`, a
//! leaf). The parameters' validation asks the safe region whether the device is safe at zero
//! bias, so `device` and `safety` lean on each other; nothing outside this folder does.

pub mod device;
pub mod failure;
pub mod material;
pub mod safety;
pub mod statics;
pub mod swing;
