//! The instruction-set trait ([`Isa`]) and the macro that compiles a table of functions once per
//! instance ([`instances!`]): the baseline one, the AVX2 one and the AVX-512 one (compiled in
//! `#[target_feature]` functions, so that the code they inline is compiled for the instance).
//!
//! Two tables use it: the chunk kernels a pass calls out of line (`phases::kernels`) and the
//! passes a substep calls (`world::passes`, the top of the kernel). Each entry is a function of
//! its own per instance with the entry's own parameters: a closure carrying them (one generic
//! `run(|| pass(..))`) lost the references' no-alias facts and made the 2D step 1.6 times as
//! long (the shape functions' lane loop stopped vectorising).
//!
//! Functions are kept to a size the optimiser handles in proportion: its time grows faster
//! than a function's size (loop rotation, full unrolling and value numbering over one large
//! body). So a chunk's gather, stencils and re-map scatter are functions of their own, called
//! once per chunk: the same code as one function per pass took 3 min 11 s to build with one
//! codegen unit, against 2 min 30 s split (benches/PERFORMANCE.md).

use super::rows::Compare;

/// An instance of the particle passes: its vectors ([`Compare`], [`super::rows::Rows`]) and
/// what differs between instances beyond them.
pub(crate) trait Isa: Compare {
    /// Whether the instance scatters on the full row configuration (`phases::p2g::rows`: two
    /// scatter functions per form rather than five). The baseline, the fallback for CPUs
    /// without AVX2 (and the instance valgrind and the fuzzer run), does, to stay small.
    const FULL_ROWS: bool;
}

impl Isa for super::Baseline {
    const FULL_ROWS: bool = true;
}

#[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
impl Isa for super::Avx2 {
    const FULL_ROWS: bool = false;
}

#[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
impl Isa for super::Avx512 {
    const FULL_ROWS: bool = false;
}

/// One wide instance of a table ([`instances!`]): the trait's implementation for `$isa`, whose
/// methods enter the module `$module` of `#[target_feature]` functions.
macro_rules! wide_instance {
    (
        $tr:ident, $isa:ident, $module:ident, $features:literal;
        $(
            fn $name:ident [$($generics:tt)*] [$($inst:ident)?] [$($garg:ident),*]
                ($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)? => $($target:ident)::+;
        )*
    ) => {
        #[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
        impl $tr for $crate::simd::$isa {
            $(
                #[inline(always)]
                fn $name<$($generics)*>($($arg: $ty),*) $(-> $ret)? {
                    // SAFETY: this instance is only chosen when the CPU and the OS support its
                    // features (`crate::simd::Simd::instance`).
                    unsafe { $module::$name::<$($garg),*>($($arg),*) }
                }
            )*
        }

        #[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
        mod $module {
            use super::*;
            $(
                // Never inlined into its caller (a chunk kernel is called per chunk): LLVM's
                // time grows faster than a function's size.
                #[inline(never)]
                #[target_feature(enable = $features)]
                pub(super) fn $name<$($generics)*>($($arg: $ty),*) $(-> $ret)? {
                    // The instance, for the entries that take it.
                    #[allow(dead_code)]
                    type I = $crate::simd::$isa;
                    $($target)::+::<$($inst,)? $($garg),*>($($arg),*)
                }
            )*
        }
    };
}
pub(crate) use wide_instance;

/// Declares the trait `$tr: $sup` with one method per entry, and its implementations: the
/// baseline one (each entry its own function), the AVX2 one and the AVX-512 one (each entry
/// compiled in a `#[target_feature]` function, [`wide_instance!`]). An entry is written once,
/// by its signature: `fn name [generics] [I] [type arguments] (parameters) -> result =>
/// target;`, where `[I]` says that the target takes the instance as its first type argument.
macro_rules! instances {
    (
        $(#[$tdoc:meta])* trait $tr:ident: $sup:path;
        $(
            $(#[$doc:meta])*
            fn $name:ident [$($generics:tt)*] [$($inst:ident)?] [$($garg:ident),*]
                ($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)? => $($target:ident)::+;
        )*
    ) => {
        $(#[$tdoc])*
        pub(crate) trait $tr: $sup {
            $($(#[$doc])* fn $name<$($generics)*>($($arg: $ty),*) $(-> $ret)?;)*
        }

        impl $tr for $crate::simd::Baseline {
            $(
                #[inline(never)]
                fn $name<$($generics)*>($($arg: $ty),*) $(-> $ret)? {
                    // The instance, for the entries that take it.
                    #[allow(dead_code)]
                    type I = $crate::simd::Baseline;
                    $($target)::+::<$($inst,)? $($garg),*>($($arg),*)
                }
            )*
        }

        $crate::simd::instances::wide_instance! {
            $tr, Avx2, avx2, "avx,avx2";
            $(fn $name [$($generics)*] [$($inst)?] [$($garg),*] ($($arg: $ty),*)
                $(-> $ret)? => $($target)::+;)*
        }
        $crate::simd::instances::wide_instance! {
            $tr, Avx512, avx512, "avx,avx2,avx512f,avx512vl,avx512bw,avx512dq";
            $(fn $name [$($generics)*] [$($inst)?] [$($garg),*] ($($arg: $ty),*)
                $(-> $ret)? => $($target)::+;)*
        }
    };
}
pub(crate) use instances;

/// Evaluates `$body` with `$isa` naming the instance that `$simd` (a [`super::Simd`]) picks
/// on this CPU: the one place that maps the choice to a type. With `form (D, K)` (the
/// dimension and stencil width of the body's form), a CPU with AVX-512 runs the AVX2
/// instance where the form has no AVX-512 one ([`super::avx512_form`]): the branch is on a
/// constant, so the AVX-512 instance of such a form is never compiled.
macro_rules! with_instance {
    // A body of no form (a scan of the particles): the AVX-512 instance wherever it is
    // compiled, as it is for the 2D three-node form in either precision.
    ($simd:expr, $isa:ident => $body:expr) => {
        $crate::simd::with_instance!($simd, form (2, 3), $isa => $body)
    };
    ($simd:expr, form ($d:expr, $k:expr), $isa:ident => $body:expr) => {
        match $simd.instance() {
            // Not in the crate's own unit-test build, which steps no world: there every pass
            // of the wide instances compiled again, 194 s of a 2-core build. The integration
            // tests (tests/kernel) link the library as users do and test every instance.
            #[cfg(all(target_arch = "x86_64", feature = "wide-simd", not(test)))]
            $crate::simd::Instance::Avx512 if const { $crate::simd::avx512_form($d, $k) } => {
                type $isa = $crate::simd::Avx512;
                $body
            }
            #[cfg(all(target_arch = "x86_64", feature = "wide-simd", not(test)))]
            $crate::simd::Instance::Avx2 | $crate::simd::Instance::Avx512 => {
                type $isa = $crate::simd::Avx2;
                $body
            }
            _ => {
                type $isa = $crate::simd::Baseline;
                $body
            }
        }
    };
}
pub(crate) use with_instance;
