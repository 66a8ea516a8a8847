//! The paper's physical parts as bond-graph fragments.
