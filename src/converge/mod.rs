//! Run time against error: the measures `bareray converge` reports for each sampling method and sample
//! count against a high-sample reference ([`metrics`]), and its log-log plot ([`plot`]).

pub mod metrics;
pub mod plot;
