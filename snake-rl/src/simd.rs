//! Runtime choice of vector instructions for the elementwise loops (tanh, Adam, gradient clipping).
//!
//! The default x86-64 target has 4-wide SSE2 only. [`dispatch`] runs a closure compiled for the
//! widest instruction set this CPU has (AVX2 + FMA on most machines since 2013, via `pulp`, which
//! checks the CPU once): the loops inside, written as plain scalar Rust, vectorise 8-wide. The
//! arithmetic is the same IEEE float32 either way: no contraction into FMA, no reordering of sums.

/// Runs `f` compiled for the CPU's best vector instructions.
#[inline(always)]
pub fn dispatch<R>(f: impl FnOnce() -> R) -> R {
    pulp::Arch::new().dispatch(f)
}
