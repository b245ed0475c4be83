//! Running a loop compiled for the widest vector instructions the CPU has.
//!
//! The solver's per-particle and per-row passes are plain loops over exact-length slices, which the
//! compiler vectorises; [`by_cpu!`] compiles such a loop three times on x86-64 (AVX-512F, AVX2 and the
//! baseline SSE2) and picks one at run time, so one binary runs everywhere and uses what it finds. The
//! results do not depend on the choice: IEEE 754 rounds vector and scalar arithmetic alike, and Rust never
//! fuses a multiply and an add on its own.

/// Defines `fn $name(args)` whose body is compiled per instruction set and chosen at run time.
macro_rules! by_cpu {
    ($(#[$meta:meta])* $vis:vis fn $name:ident $(<$(const $g:ident: $gt:ty),* $(,)?>)?
        ($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)? $body:block) => {
        $(#[$meta])*
        #[allow(clippy::too_many_arguments)]
        $vis fn $name $(<$(const $g: $gt),*>)? ($($arg: $ty),*) $(-> $ret)? {
            #[inline(always)]
            #[allow(clippy::too_many_arguments)]
            fn body $(<$(const $g: $gt),*>)? ($($arg: $ty),*) $(-> $ret)? $body
            // The one place outside `fast`'s unsafe modules where this crate calls unsafe code.
            #[cfg(target_arch = "x86_64")]
            #[allow(unsafe_code)]
            {
                #[target_feature(enable = "avx512f")]
                #[allow(clippy::too_many_arguments)]
                fn avx512 $(<$(const $g: $gt),*>)? ($($arg: $ty),*) $(-> $ret)? {
                    body $(::<$($g),*>)? ($($arg),*)
                }
                #[target_feature(enable = "avx2")]
                #[allow(clippy::too_many_arguments)]
                fn avx2 $(<$(const $g: $gt),*>)? ($($arg: $ty),*) $(-> $ret)? {
                    body $(::<$($g),*>)? ($($arg),*)
                }
                if std::arch::is_x86_feature_detected!("avx512f") {
                    // SAFETY: the CPU has AVX-512F, checked just above.
                    return unsafe { avx512 $(::<$($g),*>)? ($($arg),*) };
                }
                if std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: the CPU has AVX2, checked just above.
                    return unsafe { avx2 $(::<$($g),*>)? ($($arg),*) };
                }
            }
            body $(::<$($g),*>)? ($($arg),*)
        }
    };
}

pub(crate) use by_cpu;
