//! Which instruction set a step runs with.
//!
//! The kernel is built for the target's baseline (SSE2 on x86-64), so it runs on every CPU of
//! the target. On x86-64, with the `wide-simd` feature (on by default), the particle passes are
//! compiled twice more from the same source, for AVX2 and for AVX-512 (the latter for the
//! forms where it measured faster, `avx512_form`), and one instance is chosen at run time,
//! the widest the CPU and the operating system support:
//! - AVX and AVX2: three-operand instructions, unaligned memory operands and blends, which
//!   take about a fifth of the instructions out of the hot loops;
//! - AVX-512 (F, VL, BW and DQ): 16 lanes per register (a 3D chunk's lane loops in one, a 2D
//!   chunk's in two), and 32 vector registers. Faster on the machines measured
//!   (benches/PERFORMANCE.md).
//!
//! The gathers' arithmetic is written once on each instance's own vector type
//! (`simd::rows::Rows`: 4, 8 or 16 lanes); everything else is the same source.
//!
//! FMA is deliberately not enabled, and the kernel never calls `mul_add`: every instance rounds
//! every operation the same way, so a step gives bit-identical results on any path (tested), and
//! results do not depend on which CPU ran them.
//!
//! Process-wide caps: [`use_baseline_only`] (for tools that cannot decode the wider
//! instructions) and [`use_avx2_at_most`] (for hosts on CPUs that lower their clock while
//! 512-bit instructions run, which slows the host's other code too).
//!
//! Besides the choice (internal to the crate): the instruction sets as types (`Baseline`,
//! `Avx2`, `Avx512`), and the lane machinery every pass shares: `lanes` (chunks and lane
//! sets), `rows` (each instance's vectors, row reads and compares), `wide` (the lane type
//! with operators), `instances` (the instruction-set trait and the tables compiled per
//! instance).

pub(crate) mod instances;
pub(crate) mod lanes;
pub(crate) mod row_sums;
pub(crate) mod rows;
pub(crate) mod wide;

pub(crate) use instances::{instances, with_instance, Isa};

/// The target's baseline instruction set.
pub(crate) struct Baseline;

/// AVX and AVX2 (x86-64). Chosen only when the CPU supports them ([`Instance::Avx2`]).
#[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
pub(crate) struct Avx2;

/// AVX-512 F, VL, BW and DQ (x86-64). Chosen only when the CPU supports them
/// (`Instance::Avx512`).
#[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
pub(crate) struct Avx512;

/// The instruction-set choice for a step. Not part of the stable API: tests use it to check
/// that every path gives bit-identical state.
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Simd {
    /// The widest path the CPU supports (what [`crate::World::step`] uses).
    Detect,
    /// The widest path up to AVX2.
    Avx2,
    /// The target's baseline instructions only.
    Baseline,
}

/// The instance of the particle passes that runs.
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Instance {
    /// The target's baseline (SSE2 on x86-64).
    Baseline,
    /// AVX and AVX2 (x86-64).
    Avx2,
    /// AVX-512 F, VL, BW and DQ (x86-64).
    Avx512,
}

impl Instance {
    /// Its name in reports (`step_cost`'s JSON).
    pub fn name(self) -> &'static str {
        match self {
            Instance::Baseline => "baseline",
            Instance::Avx2 => "avx2",
            Instance::Avx512 => "avx512",
        }
    }
}

impl Simd {
    /// The widest instance this choice runs on this CPU (within the process-wide cap).
    #[inline]
    pub fn instance(self) -> Instance {
        let widest = widest();
        match self {
            Simd::Detect => widest,
            Simd::Avx2 => widest.min(Instance::Avx2),
            Simd::Baseline => Instance::Baseline,
        }
    }

    /// The instance this choice runs a world of `def` in on this CPU: [`Simd::instance`], but
    /// AVX2 in place of AVX-512 for a form that has no AVX-512 instance (`avx512_form`).
    pub fn instance_for(self, def: &crate::WorldDef) -> Instance {
        let d = if def.dimension == crate::Dimension::ThreeD {
            3
        } else {
            2
        };
        match self.instance() {
            Instance::Avx512 if !avx512_form(d, def.shape.stencil_width()) => Instance::Avx2,
            other => other,
        }
    }
}

/// Whether the AVX-512 instance of the particle passes is compiled for the form of dimension
/// `d` (2 also for the axisymmetric form) and stencils of `k` nodes per axis; where it is not,
/// a CPU with AVX-512 runs the AVX2 instance. Compiled where it measured faster than AVX2
/// (benches/PERFORMANCE.md, "AVX-512 where it pays"): in f32 every form (a 2D step 0.72 to
/// 0.81 times AVX2's, 3D 0.80 to 0.93); in f64, whose vectors hold half the lanes, the 2D
/// forms of 3 and 4 nodes (0.87 to 0.92) and the 3D cubic (0.91), not the linear forms (1.02
/// to 1.06) or the 3D 3-node one (0.97).
pub(crate) const fn avx512_form(d: usize, k: usize) -> bool {
    cfg!(not(feature = "f64")) || (k >= 3 && (d == 2 || k == 4))
}

#[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
mod state {
    use core::sync::atomic::{AtomicU8, Ordering};

    const UNKNOWN: u8 = u8::MAX;
    /// The widest instance the CPU supports (`Instance as u8`), UNKNOWN before detection.
    static DETECTED: AtomicU8 = AtomicU8::new(UNKNOWN);
    /// The process-wide cap (`Instance as u8`).
    static CAP: AtomicU8 = AtomicU8::new(super::Instance::Avx512 as u8);

    fn of(v: u8) -> super::Instance {
        match v {
            0 => super::Instance::Baseline,
            1 => super::Instance::Avx2,
            _ => super::Instance::Avx512,
        }
    }

    /// The widest instance, detected once (`cpuid` can be slow under a hypervisor), capped.
    pub fn widest() -> super::Instance {
        let mut d = DETECTED.load(Ordering::Relaxed);
        if d == UNKNOWN {
            d = super::detect() as u8;
            DETECTED.store(d, Ordering::Relaxed);
        }
        of(d.min(CAP.load(Ordering::Relaxed)))
    }

    /// Lowers the cap to `to` (never raises it).
    pub fn cap(to: super::Instance) {
        CAP.fetch_min(to as u8, Ordering::Relaxed);
    }
}

/// The widest instance this CPU runs, within the process-wide cap.
#[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
fn widest() -> Instance {
    state::widest()
}

/// Only the baseline instance on other architectures, and without the `wide-simd` feature.
#[cfg(not(all(target_arch = "x86_64", feature = "wide-simd")))]
fn widest() -> Instance {
    Instance::Baseline
}

/// Makes every later step of every world in the process run the baseline instance, whatever
/// the CPU supports. For tools that emulate the CPU and cannot decode every AVX instruction
/// (valgrind 3.19); results do not change, only speed. Irreversible for the process.
pub fn use_baseline_only() {
    #[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
    state::cap(Instance::Baseline);
}

/// Makes every later step of every world in the process run at most the AVX2 instance. For
/// hosts on CPUs that lower their clock while 512-bit instructions run (some Intel server
/// parts), where that would slow the host's other code; results do not change, only speed.
/// Irreversible for the process.
pub fn use_avx2_at_most() {
    #[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
    state::cap(Instance::Avx2);
}

/// Whether a step runs an instance wider than the baseline: the CPU and the operating system
/// support AVX and AVX2 (at least), and [`use_baseline_only`] was not called.
pub fn has_avx2() -> bool {
    widest() >= Instance::Avx2
}

/// Whether a step runs the AVX-512 instance: the CPU and the operating system support
/// AVX-512 F, VL, BW and DQ, and neither cap was set.
pub fn has_avx512() -> bool {
    widest() == Instance::Avx512
}

/// The widest instance the CPU and the operating system support, as the Intel and AMD manuals
/// prescribe: CPUID leaf 1 (ECX bit 27 OSXSAVE, bit 28 AVX) and XCR0 bits 1-2 (the OS saves the
/// XMM and YMM registers), CPUID leaf 7 EBX bit 5 (AVX2); for AVX-512, XCR0 bits 5-7 (the
/// opmask registers and the upper ZMM state) and leaf 7 EBX bits 16 (F), 17 (DQ), 30 (BW) and
/// 31 (VL).
#[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
fn detect() -> Instance {
    use core::arch::x86_64::{__cpuid, __cpuid_count, _xgetbv};
    let max_leaf = __cpuid(0).eax;
    if max_leaf < 7 {
        return Instance::Baseline;
    }
    let ecx = __cpuid(1).ecx;
    let (osxsave, avx) = (ecx & (1 << 27) != 0, ecx & (1 << 28) != 0);
    if !(osxsave && avx) {
        return Instance::Baseline;
    }
    // SAFETY: OSXSAVE is set, so XGETBV is available and XCR0 readable.
    let xcr0 = unsafe { _xgetbv(0) };
    if xcr0 & 0b110 != 0b110 {
        return Instance::Baseline;
    }
    let ebx = __cpuid_count(7, 0).ebx;
    if ebx & (1 << 5) == 0 {
        return Instance::Baseline;
    }
    let avx512 = (1 << 16) | (1 << 17) | (1 << 30) | (1 << 31);
    if xcr0 & 0b1110_0000 == 0b1110_0000 && ebx & avx512 == avx512 {
        Instance::Avx512
    } else {
        Instance::Avx2
    }
}
