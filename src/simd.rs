//! The SIMD level queries run at, chosen when the program runs.
//!
//! A plain `cargo build` for x86-64 targets the baseline (SSE2), because the binary must run on
//! every x86-64 CPU. raylane's queries nevertheless run the widest instructions the CPU has:
//! every [`Query`](crate::Query) enters one of three copies of the same generic code,
//! compiled for
//!
//! | [`Level`] | instructions | when |
//! | --- | --- | --- |
//! | [`Level::Baseline`] | SSE2 (x86-64), NEON (AArch64), the target's own elsewhere | always |
//! | [`Level::Avx2`] | x86-64-v3: AVX2, FMA, BMI1/2, LZCNT, MOVBE, F16C | the CPU and the OS support them |
//! | [`Level::Avx512`] | x86-64-v4: the above and AVX-512 F, BW, CD, DQ, VL | likewise |
//!
//! The level is detected once (`cpuid`, and `xgetbv` for the OS's saving of the vector
//! registers; no `std` needed) and chosen at the query's entry, never per node or kernel.
//! Below the entry nothing knows about levels: the code is the crate's one generic body, with
//! a packet's lanes in the level's vectors ([`with_lanes`]: at AVX2 and AVX-512 one AVX
//! register for 8 lanes, two for 16, with the level's instructions; `wide`'s at the baseline) and a BVH
//! node's 8 children in [`X8`](crate::lane::X8), and every operation a correctly rounded IEEE
//! operation with no fused multiply-add. **Every level gives the same bits**; only a BVH's box
//! test, which only prunes, may differ in which boxes it opens (fused where the build itself
//! targets FMA, see [`bvh`](crate::bvh)).
//!
//! Packets asked of an instanced scene ([`Scene`](crate::bvh::Scene),
//! `OwnedScene`) run in the caller's lanes at the build's own level
//! ([`Trace::LEVEL_LANES`](crate::set::Trace::LEVEL_LANES)); their single rays enter the level.
//!
//! The BVH build and the baker are not dispatched: they run at the build's own level, and a
//! default build builds as fast as a build for the CPU (scenes benchmark, this AMD EPYC, one
//! run each: 0.9 / 0.8 ms for the vendored bunny, 320.8 / 330.3 ms for Loop×4, 33.4 / 30.7 ms
//! for 10^5 spheres; baking 691.8 / 663.3 ms for Loop×4; benches/RESULTS.md).
//!
//! A build for the CPU (`-C target-cpu=native`) or for a level (`x86-64-v3`) already runs
//! those instructions everywhere: the entry then calls the code directly. Other targets
//! (AArch64, whose baseline is NEON; Cortex-M; RISC-V) have one level and compile what they
//! always did.
//!
//! **Forcing a level** (tests and benchmarks): [`force`], or with feature `std` the environment
//! variable `RAYLANE_SIMD` (`baseline`, `avx2` or `avx512`), read at the first query. A level
//! the CPU lacks is refused ([`Unsupported`]; the variable then leaves the detected level
//! and prints a warning), never executed.
//!
//! ```
//! // What this machine runs, and that forcing the baseline always works.
//! let best = raylane::simd::level();
//! assert!(raylane::simd::supported(best));
//! raylane::simd::force(raylane::simd::Level::Baseline).unwrap();
//! assert_eq!(raylane::simd::level(), raylane::simd::Level::Baseline);
//! raylane::simd::force(best).unwrap();
//! ```

use core::sync::atomic::{AtomicU8, Ordering};

use crate::lane::Lane;

/// A SIMD level (see the [module docs](self)).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Level {
    /// The target's baseline: SSE2 on x86-64, NEON on AArch64.
    Baseline,
    /// x86-64-v3: AVX2 and FMA (and BMI1/2, LZCNT, MOVBE, F16C).
    Avx2,
    /// x86-64-v4: x86-64-v3 and AVX-512 F, BW, CD, DQ, VL.
    Avx512,
}

impl Level {
    /// Every level, lowest first.
    pub const ALL: [Level; 3] = [Level::Baseline, Level::Avx2, Level::Avx512];

    /// What it is called, as `RAYLANE_SIMD` takes it: `baseline`, `avx2`, `avx512`.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Level::Baseline => "baseline",
            Level::Avx2 => "avx2",
            Level::Avx512 => "avx512",
        }
    }

    /// The level called `name` (see [`name`](Self::name)).
    #[must_use]
    pub fn from_name(name: &str) -> Option<Level> {
        Level::ALL.into_iter().find(|l| l.name() == name)
    }

    /// The instructions it runs, for people: `SSE2`, `AVX2+FMA`, `AVX-512` (x86-64), `NEON`
    /// (AArch64), `scalar` elsewhere.
    #[must_use]
    pub const fn describe(self) -> &'static str {
        match self {
            Level::Avx2 => "AVX2+FMA",
            Level::Avx512 => "AVX-512",
            Level::Baseline if cfg!(target_arch = "x86_64") => "SSE2",
            Level::Baseline if cfg!(target_arch = "aarch64") => "NEON",
            Level::Baseline => "scalar",
        }
    }

    /// f32 lanes per register at this level: 4, 8 or 16 (1 without SIMD).
    #[must_use]
    pub const fn lanes(self) -> usize {
        match self {
            Level::Avx512 => 16,
            Level::Avx2 => 8,
            Level::Baseline if cfg!(any(target_arch = "x86_64", target_arch = "aarch64")) => 4,
            Level::Baseline => 1,
        }
    }
}

impl core::fmt::Display for Level {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.describe())
    }
}

/// A level the CPU (or the target) does not support: refused by [`force`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Unsupported(pub Level);

impl core::fmt::Display for Unsupported {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "this CPU does not support the SIMD level {}",
            self.0.name()
        )
    }
}

/// The chosen level: 0 until detected, else `Level as u8 + 1`.
static CHOSEN: AtomicU8 = AtomicU8::new(0);

/// The level queries run at: the best the CPU supports, unless [`force`]d (or, with `std`,
/// set by `RAYLANE_SIMD`). Detected at the first call.
#[inline]
#[must_use]
pub fn level() -> Level {
    match CHOSEN.load(Ordering::Relaxed) {
        2 => Level::Avx2,
        3 => Level::Avx512,
        1 => Level::Baseline,
        _ => choose(),
    }
}

/// Runs queries at `level` from now on, in every thread.
///
/// # Errors
///
/// [`Unsupported`] when the CPU lacks it (nothing changes).
pub fn force(level: Level) -> Result<(), Unsupported> {
    if !supported(level) {
        return Err(Unsupported(level));
    }
    CHOSEN.store(level as u8 + 1, Ordering::Relaxed);
    Ok(())
}

/// True when this CPU (and target) can run `level`.
#[must_use]
pub fn supported(level: Level) -> bool {
    level <= best()
}

/// Detects, applies `RAYLANE_SIMD` (with `std`), stores and returns the level.
#[cold]
fn choose() -> Level {
    #[cfg_attr(not(feature = "std"), allow(unused_mut))]
    let mut chosen = best();
    #[cfg(feature = "std")]
    if let Ok(name) = std::env::var("RAYLANE_SIMD") {
        match Level::from_name(name.trim()) {
            Some(l) if supported(l) => chosen = l,
            Some(l) => std::eprintln!(
                "raylane: RAYLANE_SIMD={name}: {}; running {}",
                Unsupported(l),
                chosen.name()
            ),
            None => std::eprintln!(
                "raylane: RAYLANE_SIMD={name} is not a level (baseline, avx2, avx512); running {}",
                chosen.name()
            ),
        }
    }
    CHOSEN.store(chosen as u8 + 1, Ordering::Relaxed);
    chosen
}

/// The best level of this CPU (the compile-time features count as present).
fn best() -> Level {
    #[cfg(target_arch = "x86_64")]
    {
        x86::best()
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        Level::Baseline
    }
}

/// Runs `f` compiled for the chosen [`level`]: the queries' entry (see the
/// [module docs](self)). `f` and everything it calls should be `#[inline(always)]` (the
/// crate's query paths are): what is not inlined into the level's copy runs at the baseline
/// (the same answers, slower).
#[inline(always)]
pub fn run<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    {
        x86::run(level(), f)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        f()
    }
}

/// Asks the CPU to bring `x` (every cache line it spans) into its caches, without waiting
/// for it: x86-64's `prefetcht0`; nothing on other targets. It reads nothing and changes no
/// answer. (Its one caller is the owned scene's, hence `alloc`.)
#[cfg(feature = "alloc")]
#[inline(always)]
pub(crate) fn prefetch<T>(x: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use core::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let p = (x as *const T).cast::<i8>();
        // The most lines a `T` spans at any address its alignment allows (a constant).
        let lines = (size_of::<T>() + 64 - align_of::<T>().min(64)).div_ceil(64);
        for k in 0..lines {
            // SAFETY: a prefetch of any address is allowed and reads nothing.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(64 * k)) }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}

/// Code generic over the lane type of a packet: what [`with_lanes`] runs. Its
/// [`run`](Self::run) gets the lanes of the chosen level for the width asked.
pub trait Packets {
    /// What it returns.
    type Output;
    /// Runs with packets in `L` (`L::LANES` the width asked).
    fn run<L: Lane<Scalar = f32>>(self) -> Self::Output;
}

/// Runs `f` compiled for the chosen [`level`], with packets of `lanes` lanes (1, 4, 8 or 16;
/// any other width runs 16) in that level's vectors: on x86-64 at [`Level::Avx2`] and
/// [`Level::Avx512`] raylane's own AVX types for 8 and 16 lanes (one and two registers,
/// compiled with the level's instructions: one AVX-512 register for 16 lanes was measured
/// slower, see docs/design.md); `wide`'s vectors at the baseline and for 4 lanes; `f32` for 1. The queries enter here: a packet of `wide::f32x8` is converted in and its records
/// out, bit for bit.
///
/// The level's own types exist only on a CPU that has the level: code outside the crate meets
/// them only as `run`'s type parameter (they have no name there). `f`'s `run` should be
/// `#[inline(always)]` down to its loops, like the crate's query paths (see [`run`]).
#[inline(always)]
pub fn with_lanes<F: Packets>(lanes: usize, f: F) -> F::Output {
    match lanes {
        1 => with_lanes_of::<f32, F>(f),
        4 => with_lanes_of::<wide::f32x4, F>(f),
        8 => with_lanes_of::<wide::f32x8, F>(f),
        _ => with_lanes_of::<wide::f32x16, F>(f),
    }
}

/// [`with_lanes`] for packets of `L`'s width, a constant: only that width's copies are
/// compiled (one per level), where a width known at run time compiles every width's (the
/// queries enter here; their packets' width is their type's).
#[inline(always)]
pub(crate) fn with_lanes_of<L: Lane, F: Packets>(f: F) -> F::Output {
    #[cfg(target_arch = "x86_64")]
    {
        x86::with_lanes_of::<L, F>(level(), f)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        if const { L::LANES == 1 } {
            f.run::<f32>()
        } else if const { L::LANES == 4 } {
            f.run::<wide::f32x4>()
        } else if const { L::LANES == 8 } {
            f.run::<wide::f32x8>()
        } else {
            f.run::<wide::f32x16>()
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::{Level, Packets};
    use crate::lane::Lane;
    use crate::lane::{Y8, Y16};

    /// [`super::with_lanes_of`] at `level`. The width is a constant (`if const`): the other
    /// widths' branches are not compiled, so a query has three copies (one per level).
    #[inline(always)]
    pub(super) fn with_lanes_of<L: Lane, F: Packets>(level: Level, f: F) -> F::Output {
        if const { L::LANES == 1 } {
            run(
                level,
                #[inline(always)]
                || f.run::<f32>(),
            )
        } else if const { L::LANES == 4 } {
            run(
                level,
                #[inline(always)]
                || f.run::<wide::f32x4>(),
            )
        } else if const { L::LANES == 8 } {
            // Avx2 and Avx512 only where `best()` found them (`force` refuses more): the AVX
            // types' instructions exist on this CPU.
            match level {
                Level::Baseline => f.run::<wide::f32x8>(),
                Level::Avx2 => at_v3(
                    #[inline(always)]
                    || f.run::<Y8>(),
                ),
                Level::Avx512 => at_v4(
                    #[inline(always)]
                    || f.run::<Y8>(),
                ),
            }
        } else {
            match level {
                Level::Baseline => f.run::<wide::f32x16>(),
                Level::Avx2 => at_v3(
                    #[inline(always)]
                    || f.run::<Y16>(),
                ),
                Level::Avx512 => at_v4(
                    #[inline(always)]
                    || f.run::<Y16>(),
                ),
            }
        }
    }

    /// `f` in its x86-64-v3 copy; only at [`Level::Avx2`] or above.
    #[inline(always)]
    fn at_v3<R>(f: impl FnOnce() -> R) -> R {
        if const { BUILT_V3 } {
            f()
        } else {
            // SAFETY: called at `level()` Avx2 or Avx512 only, which `best()` returns when it
            // found every v3 feature in `cpuid` and the OS saving the AVX state in XCR0.
            unsafe { v3(f) }
        }
    }

    /// `f` in its x86-64-v4 copy; only at [`Level::Avx512`].
    #[inline(always)]
    fn at_v4<R>(f: impl FnOnce() -> R) -> R {
        if const { BUILT_V4 } {
            f()
        } else {
            // SAFETY: called at `level()` Avx512 only, which `best()` returns when it found
            // every v4 feature in `cpuid` and the OS saving the AVX-512 state in XCR0.
            unsafe { v4(f) }
        }
    }

    /// True when the build itself targets AVX-512 (or only AVX2): no run-time copies needed.
    const BUILT_V4: bool = cfg!(all(
        target_feature = "avx512f",
        target_feature = "avx512bw",
        target_feature = "avx512cd",
        target_feature = "avx512dq",
        target_feature = "avx512vl",
        target_feature = "avx2",
        target_feature = "fma",
    ));
    const BUILT_V3: bool = cfg!(all(target_feature = "avx2", target_feature = "fma"));

    /// The level of `f`'s copy: [`Level::Avx512`] and [`Level::Avx2`] run the copies compiled
    /// for them (the caller checked the CPU through [`super::level`]).
    #[inline(always)]
    pub(super) fn run<R>(level: Level, f: impl FnOnce() -> R) -> R {
        if BUILT_V4 {
            return f();
        }
        match level {
            // SAFETY: `level()` returns Avx512 only when `best()` found every v4 feature in
            // `cpuid` and the OS saving the AVX-512 state in XCR0 (`force` refuses more).
            Level::Avx512 => unsafe { v4(f) },
            // SAFETY: likewise for the v3 features and the AVX state.
            Level::Avx2 if !BUILT_V3 => unsafe { v3(f) },
            _ => f(),
        }
    }

    /// `f` compiled for x86-64-v3.
    #[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,movbe,f16c,popcnt")]
    unsafe fn v3<R>(f: impl FnOnce() -> R) -> R {
        f()
    }

    /// `f` compiled for x86-64-v4.
    #[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,movbe,f16c,popcnt")]
    #[target_feature(enable = "avx512f,avx512bw,avx512cd,avx512dq,avx512vl")]
    unsafe fn v4<R>(f: impl FnOnce() -> R) -> R {
        f()
    }

    /// The best level from `cpuid` and `xgetbv` (no `std` needed).
    pub(super) fn best() -> Level {
        if BUILT_V4 {
            return Level::Avx512;
        }
        use core::arch::x86_64::{__cpuid, __cpuid_count};
        let bit = |x: u32, b: u32| x & (1 << b) != 0;
        // SAFETY: `cpuid` exists on every x86-64 CPU; leaves 1 and 7 exist when leaf 0's
        // maximum says so (checked), and 0x8000_0001 when 0x8000_0000's does.
        #[allow(unused_unsafe)]
        let (max, max_ext) = unsafe { (__cpuid(0).eax, __cpuid(0x8000_0000).eax) };
        if max < 7 || max_ext < 0x8000_0001 {
            return Level::Baseline;
        }
        // SAFETY: as above.
        #[allow(unused_unsafe)]
        let (l1, l7, ext) = unsafe { (__cpuid(1), __cpuid_count(7, 0), __cpuid(0x8000_0001)) };
        // The OS saves the vector registers (XCR0) only if it set OSXSAVE.
        if !bit(l1.ecx, 27) {
            return Level::Baseline;
        }
        // SAFETY: OSXSAVE is set, so `xgetbv` exists and XCR0 is readable.
        let xcr0 = unsafe { xcr0() };
        let ymm = xcr0 & 0b110 == 0b110;
        let zmm = xcr0 & 0b1110_0110 == 0b1110_0110;
        let v3 = ymm
            && bit(l1.ecx, 28) // AVX
            && bit(l1.ecx, 12) // FMA
            && bit(l1.ecx, 22) // MOVBE
            && bit(l1.ecx, 23) // POPCNT
            && bit(l1.ecx, 29) // F16C
            && bit(l7.ebx, 5) // AVX2
            && bit(l7.ebx, 3) // BMI1
            && bit(l7.ebx, 8) // BMI2
            && bit(ext.ecx, 5); // LZCNT
        let v4 = v3
            && zmm
            && bit(l7.ebx, 16) // AVX512F
            && bit(l7.ebx, 17) // AVX512DQ
            && bit(l7.ebx, 28) // AVX512CD
            && bit(l7.ebx, 30) // AVX512BW
            && bit(l7.ebx, 31); // AVX512VL
        if v4 {
            Level::Avx512
        } else if v3 || BUILT_V3 {
            Level::Avx2
        } else {
            Level::Baseline
        }
    }

    /// XCR0, the state components the OS saves.
    #[target_feature(enable = "xsave")]
    unsafe fn xcr0() -> u64 {
        // SAFETY: the caller checked OSXSAVE; reading XCR0 has no side effect.
        unsafe { core::arch::x86_64::_xgetbv(0) }
    }
}
