//! LU factorisation of the iteration matrices that uses their sparsity: bordered
//! block-diagonal (Schur complement) elimination, with the dense LU as its special case.
//!
//! Both methods solve with a matrix `M = c I - J` (Rodas5P: real c = 1/(h γ); Radau5: a real
//! and a complex one). In a model whose parts meet only at a few states (the plate's modes
//! meet only at the hub and the torsion bar), most states form small groups that are coupled
//! with each other only through a few *border* states. Ordered group after group with the border
//! last, M is bordered block-diagonal ("arrowhead"):
//!
//! ```text
//!     [ A_1           B_1 ]
//!     [      ...      ... ]      A_b: small square blocks (a group's states)
//! M = [           A_k B_k ]      D:   the border (m × m)
//!     [ C_1  ...  C_k  D  ]
//! ```
//!
//! and it is factorised block by block: an LU with partial pivoting of every A_b,
//! X_b = A_b⁻¹ B_b, and a dense LU of the Schur complement S = D - Σ C_b X_b. A solve is then
//! a forward pass over the blocks, a solve with S for the border, and a back substitution
//! x_b = y_b - X_b x_border. Work and memory grow with Σ k_b³ + m³ (factorisation) and
//! Σ k_b² + m² (solve) plus the couplings, instead of n³ and n².
//!
//! [`Partition::detect`] finds the groups and the border from the nonzero pattern of J alone
//! (nothing about the model): it moves the state with the most neighbours into the border until
//! the estimated work stops falling, and keeps the best split it saw; if that split does not
//! save at least half of the dense work it returns the dense partition (one block holding every
//! state, no border), which is an ordinary LU with partial pivoting. The elimination does not
//! pivot across blocks, so a block whose pivots are small against its own entries, its rows and
//! columns scaled to a largest entry of 1 (or an exactly singular one), makes
//! [`Factorisation::factor`] report failure; the caller then factorises with the dense
//! partition, which fails only if M is singular.
//!
//! Everything is deterministic (the same J gives the same partition and the same bits), which
//! keeps a restored integrator, which refactorises, bit-identical to the original.
//! [`Factorisation::factor`] reuses the memory of the previous factorisation, and
//! [`Factorisation::solve`] takes the caller's scratch vector, so neither allocates once warm.
//!
//! The module is split by job: [`Scalar`] (the entries' type), the partition's layout
//! (`partition`) and its search ([`Partition::detect`], `detect`), the block elimination
//! ([`Factorisation`], `factorisation`) and the solve with its factors (`factorisation::solve`),
//! the dense LU kernels of a block (`lu`), and the
//! cache of the last Jacobian's partition (`pattern`). [`VaryingRows`] is the other
//! elimination, for a fixed step size whose Jacobian varies in a few rows only: the constant
//! rows eliminated once, a small Schur complement of the varying ones at every step.

// Index loops mirror the elimination formulas.
#![allow(clippy::needless_range_loop)]

mod detect;
mod factorisation;
mod lu;
mod partition;
mod pattern;
mod scalar;
#[cfg(test)]
mod testing;
mod varying_rows;

pub(crate) use factorisation::factor_with_fallback;
pub use factorisation::{Entries, Factorisation, Shifted};
#[cfg(target_arch = "x86_64")]
pub(crate) use lu::PARTIAL_MASKS;
pub use partition::Partition;
pub(crate) use pattern::PatternCache;
pub use scalar::Scalar;
pub use varying_rows::VaryingRows;
