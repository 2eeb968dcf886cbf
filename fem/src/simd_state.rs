//! The SIMD register state left by faer's kernels, cleared before Loam's scalar code runs.
//!
//! faer's dense kernels (through `pulp`) run AVX2 code on 256-bit registers and return with
//! the upper halves of those registers in use. Loam's own code is compiled for the x86-64
//! baseline, whose floating-point instructions are SSE (non-VEX); on x86 cores an SSE
//! instruction executed while the upper halves are dirty pays a transition penalty or a false
//! dependency on them (Intel, "Avoiding AVX-SSE Transition Penalties"; Intel 64 and IA-32
//! Architectures Optimization Reference Manual, §15.3), until a `VZEROUPPER`. Measured on the
//! Bui collapse (issue 30): the assembly after a factorisation ran 1.9× slower (14.45 s
//! against 7.67 s over the same 5 061 Newton iterations), the triangular solves 2.2× slower.
//! [`clear_upper_state`] executes one 256-bit operation inside a function compiled for AVX2
//! (`pulp`'s safe `V3::vectorize`), at whose return the compiler emits `VZEROUPPER`.

/// Leaves the upper halves of the 256-bit registers clean (a `VZEROUPPER`) on x86-64 cores
/// with AVX2; nothing elsewhere. Call after faer's kernels, before scalar code.
#[inline]
pub fn clear_upper_state() {
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = pulp::x86::V3::try_new() {
        simd.vectorize(|| {
            std::hint::black_box(simd.splat_f64x4(std::hint::black_box(0.0)));
        });
    }
}
