//! Subnormal numbers flushed to zero while mstar computes.
//!
//! A disturbance that decays along a long chain (a chain started at rest,
//! pinned at one end) leaves values of 1e-300 and below in thousands of
//! coordinates for the first hundreds of steps, and their products are
//! subnormal: on x86-64 an operation with a subnormal operand or result
//! takes a microcode assist of about a hundred cycles. The spatial bar
//! chain of 10³ bodies stepped its first 0.1 s at 1.01 µs a body-step and
//! its steps after the first second at about 0.75 (docs/performance.md,
//! "Subnormal numbers").
//!
//! [`FlushSubnormals`] sets the flush-to-zero and denormals-are-zero modes
//! of the SSE control register (MXCSR) for the current thread and restores
//! the caller's modes when dropped, so that a program using mstar (Python,
//! say) keeps IEEE arithmetic outside mstar's calls (a system's own code
//! called inside them, the closures of a [`crate::FnSystem`], runs under
//! the same modes). A value below
//! `f64::MIN_POSITIVE` (2.2e-308) then reads and is written as zero: a
//! change far below every tolerance and round-off of a multibody
//! computation. On other targets it does nothing.

/// The flush-to-zero (bit 15) and denormals-are-zero (bit 6) modes of MXCSR.
#[cfg(target_arch = "x86_64")]
const FTZ_DAZ: u32 = (1 << 15) | (1 << 6);

/// While alive, the current thread flushes subnormal operands and results
/// to zero (module documentation); dropping it restores the modes it found.
#[must_use = "the modes are restored when the guard is dropped"]
pub struct FlushSubnormals {
    /// The control register as found.
    #[cfg(target_arch = "x86_64")]
    saved: u32,
}

impl FlushSubnormals {
    /// Sets the modes for the current thread.
    pub fn new() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            let saved = mxcsr::read();
            if saved & FTZ_DAZ != FTZ_DAZ {
                mxcsr::write(saved | FTZ_DAZ);
            }
            Self { saved }
        }
        #[cfg(not(target_arch = "x86_64"))]
        Self {}
    }
}

/// Whether the current thread flushes subnormals to zero (both modes set):
/// what work handed to other threads sets there with [`FlushSubnormals`],
/// so that it computes as the calling thread would.
#[must_use]
pub fn flushing() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        mxcsr::read() & FTZ_DAZ == FTZ_DAZ
    }
    #[cfg(not(target_arch = "x86_64"))]
    false
}

impl Default for FlushSubnormals {
    fn default() -> Self {
        Self::new()
    }
}

impl Drop for FlushSubnormals {
    fn drop(&mut self) {
        #[cfg(target_arch = "x86_64")]
        if self.saved & FTZ_DAZ != FTZ_DAZ {
            mxcsr::write(self.saved);
        }
    }
}

/// Reading and writing the SSE control and status register.
#[cfg(target_arch = "x86_64")]
mod mxcsr {
    use std::arch::asm;

    /// The register's value (`stmxcsr`).
    pub(super) fn read() -> u32 {
        let mut value: u32 = 0;
        // SAFETY: stores the 32-bit register into `value`, a valid,
        // aligned u32 that outlives the instruction.
        unsafe {
            asm!("stmxcsr [{}]", in(reg) &raw mut value, options(nostack, preserves_flags));
        }
        value
    }

    /// Loads `value` into the register (`ldmxcsr`). The callers only set or
    /// clear the FTZ and DAZ bits of a value read from it, so no reserved
    /// bit is set (which would fault).
    pub(super) fn write(value: u32) {
        // SAFETY: loads the register from `value`, a valid, aligned u32; it
        // changes only how this thread's later floating-point operations
        // treat subnormals.
        unsafe {
            asm!("ldmxcsr [{}]", in(reg) &raw const value, options(nostack, readonly, preserves_flags));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::FlushSubnormals;
    use std::hint::black_box;

    /// The smallest normal number halved: subnormal under IEEE arithmetic,
    /// zero under the guard, subnormal again after it.
    #[test]
    fn subnormals_are_flushed_inside_the_guard_only() {
        let half = |x: f64| black_box(x) * black_box(0.5);
        let before = half(f64::MIN_POSITIVE);
        assert!(before > 0.0 && before < f64::MIN_POSITIVE, "{before:e}");
        assert!(!super::flushing());
        {
            let _guard = FlushSubnormals::new();
            assert_eq!(super::flushing(), cfg!(target_arch = "x86_64"));
            let inside = half(f64::MIN_POSITIVE);
            if cfg!(target_arch = "x86_64") {
                assert_eq!(inside, 0.0);
                // Denormals-are-zero: a subnormal operand reads as zero.
                assert_eq!(black_box(before) * black_box(4.0), 0.0);
                // Nested guards restore the modes of the outer one.
                {
                    let _inner = FlushSubnormals::new();
                }
                assert_eq!(half(f64::MIN_POSITIVE), 0.0);
            }
            // Normal numbers are untouched.
            assert_eq!(half(3.0), 1.5);
        }
        assert_eq!(half(f64::MIN_POSITIVE), before);
        assert!(!super::flushing());
    }
}
