//! Explicit dynamics of the FE bodies (issue 4, in progress): corotational Q8 bodies with lumped
//! mass, central-difference integration, critical time step, energy balance. Contact, hubs and
//! the meshing-pair scenes come next.

pub mod body;
pub mod pair;
pub mod scene;
pub mod solver;
