//! Which instruction set a step runs with.
//!
//! The kernel is built for the target's baseline (SSE2 on x86-64), so it runs on every CPU of
//! the target. On x86-64 the step is compiled a second time with AVX and AVX2 enabled and chosen
//! at run time when the CPU has them: the same source, with three-operand instructions, unaligned
//! memory operands and blends, which take about a fifth of the instructions out of the hot
//! loops. FMA is deliberately not enabled, and the kernel never calls `mul_add`: both instances
//! round every operation the same way, so a step gives bit-identical results on either path
//! (tested), and results do not depend on which CPU ran them.

/// The instruction-set choice for a step. Not part of the stable API: tests use it to check
/// that both paths give bit-identical state.
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Simd {
    /// The widest path the CPU supports (what [`crate::World::step`] uses).
    Detect,
    /// The target's baseline instructions only.
    Baseline,
}

impl Simd {
    /// Whether this choice runs the AVX2 instance on this CPU.
    #[inline]
    pub fn uses_avx2(self) -> bool {
        self == Simd::Detect && has_avx2()
    }
}

#[cfg(target_arch = "x86_64")]
mod state {
    use core::sync::atomic::AtomicU8;
    pub const UNKNOWN: u8 = 0;
    pub const NO: u8 = 1;
    pub const YES: u8 = 2;
    /// The detection result, or NO after [`super::use_baseline_only`].
    pub static STATE: AtomicU8 = AtomicU8::new(UNKNOWN);
}

/// Makes every later step of every world in the process run the baseline instance, whatever
/// the CPU supports. For tools that emulate the CPU and cannot decode every AVX instruction
/// (valgrind 3.19); results do not change, only speed.
pub fn use_baseline_only() {
    #[cfg(target_arch = "x86_64")]
    state::STATE.store(state::NO, core::sync::atomic::Ordering::Relaxed);
}

/// Whether the CPU and the operating system support AVX and AVX2 (cached after the first call:
/// `cpuid` can be slow under a hypervisor), and [`use_baseline_only`] was not called.
#[cfg(target_arch = "x86_64")]
pub fn has_avx2() -> bool {
    use core::sync::atomic::Ordering;
    use state::{NO, STATE, YES};
    match STATE.load(Ordering::Relaxed) {
        YES => true,
        NO => false,
        _ => {
            let yes = detect_avx2();
            STATE.store(if yes { YES } else { NO }, Ordering::Relaxed);
            yes
        }
    }
}

/// No second instance on other architectures.
#[cfg(not(target_arch = "x86_64"))]
pub fn has_avx2() -> bool {
    false
}

/// CPUID leaf 1 (ECX bit 27 OSXSAVE, bit 28 AVX), XCR0 bits 1-2 (the OS saves the XMM and YMM
/// registers) and CPUID leaf 7 (EBX bit 5 AVX2), as the Intel and AMD manuals prescribe.
#[cfg(target_arch = "x86_64")]
fn detect_avx2() -> bool {
    use core::arch::x86_64::{__cpuid, __cpuid_count, _xgetbv};
    let max_leaf = __cpuid(0).eax;
    if max_leaf < 7 {
        return false;
    }
    let ecx = __cpuid(1).ecx;
    let (osxsave, avx) = (ecx & (1 << 27) != 0, ecx & (1 << 28) != 0);
    if !(osxsave && avx) {
        return false;
    }
    // SAFETY: OSXSAVE is set, so XGETBV is available and XCR0 readable.
    let xcr0 = unsafe { _xgetbv(0) };
    if xcr0 & 0b110 != 0b110 {
        return false;
    }
    __cpuid_count(7, 0).ebx & (1 << 5) != 0
}
