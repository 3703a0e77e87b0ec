pub mod adjoint;
pub mod forward;
pub mod traits;

pub use adjoint::AdjointOde;
pub use forward::ForwardSensitivityOde;
pub use traits::{ParametrizedODE, ParametrizedOdeFnWrapper};
