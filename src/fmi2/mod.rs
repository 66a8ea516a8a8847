//! The FMI 2.0 co-simulation C ABI.
