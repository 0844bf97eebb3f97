//! Helpers shared by the lab's test modules, and the binary's counting global allocator.

pub mod adaptive;
pub mod cli;
pub mod distance;
pub mod robust;
pub mod scenes;
pub mod systems;

#[path = "../../../tests/common/counting.rs"]
pub mod counting;
#[path = "../../../tests/common/kepler_periapsis.rs"]
pub mod kepler_periapsis;
