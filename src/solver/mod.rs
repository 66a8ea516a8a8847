//! Stiff one-step integrators. (Being written: issue "Stiff integrator".)
