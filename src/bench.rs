//! The peer-benchmark workloads (to be written).
