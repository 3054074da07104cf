//! Optimizer: fused Adam over every Gaussian parameter group, with moments on the GPU that
//! survive changes of the Gaussian set, and the learning-rate schedules.

mod adam;
mod schedule;

pub use adam::{Adam, AdamParams, LearningRates, NEW_ROW};
pub use schedule::exponential_decay;
