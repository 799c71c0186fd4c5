//! Joint kernels in chunks for rayon: the planar revolute and the spatial
//! spherical kernels of long chains are evaluated in parallel parts that
//! write disjoint rows and values.

/// The fewest joints in one parallel chunk.
pub(crate) const PARALLEL_CHUNK: usize = 2048;

use rayon::prelude::*;

use crate::subnormal::{self, FlushSubnormals};

/// A kernel that knows where its output starts.
pub(crate) trait KernelOffsets {
    /// The global row, `B` value and Hessian value at which its output starts.
    fn offsets(&self) -> (usize, usize, usize);
}

/// A chunk of kernels and the offsets at which its output part starts.
pub(crate) type Part<'a, K> = (&'a [K], (usize, usize, usize));

/// `kernels` in chunks for rayon, each with the global row, `B` value and
/// Hessian value at which its output part starts (0 for the first chunk);
/// empty when the work is sequential: fewer than two chunks' worth of
/// joints, or one thread in rayon's current pool.
pub(crate) fn parallel_parts<K: KernelOffsets>(kernels: &[K]) -> Vec<Part<'_, K>> {
    let threads = rayon::current_num_threads();
    if threads < 2 || kernels.len() < 2 * PARALLEL_CHUNK {
        return Vec::new();
    }
    let size = kernels.len().div_ceil(4 * threads).max(PARALLEL_CHUNK);
    kernels
        .chunks(size)
        .enumerate()
        .map(|(i, ks)| (ks, if i == 0 { (0, 0, 0) } else { ks[0].offsets() }))
        .collect()
}

/// Splits `x` into consecutive parts starting at `bases` (the first part at 0
/// whatever the first base says; bases ascending).
pub(crate) fn split_at_bases(x: &mut [f64], bases: impl Iterator<Item = usize>) -> Vec<&mut [f64]> {
    let mut parts = Vec::new();
    let (mut rest, mut at) = (x, 0);
    for base in bases.skip(1) {
        let (head, tail) = rest.split_at_mut(base - at);
        parts.push(head);
        (rest, at) = (tail, base);
    }
    parts.push(rest);
    parts
}

/// `Φ` and `B` of `kernels`: `each(kernel, phi, b, (row, value))` writes a
/// kernel's rows of `phi` and values of `b`, the slices starting at global
/// row `row` and value `value`; in parallel [`parallel_parts`] when there
/// are any (each kernel writes only its own rows and values, so the parts
/// never overlap), else in order over the whole slices.
pub(crate) fn phi_b_in_parts<K: KernelOffsets + Sync>(
    kernels: &[K],
    phi: &mut [f64],
    b: &mut [f64],
    each: impl Fn(&K, &mut [f64], &mut [f64], (usize, usize)) + Sync,
) {
    let parts = parallel_parts(kernels);
    if parts.is_empty() {
        for k in kernels {
            each(k, phi, b, (0, 0));
        }
        return;
    }
    let phi_parts = split_at_bases(phi, parts.iter().map(|p| p.1.0));
    let b_parts = split_at_bases(b, parts.iter().map(|p| p.1.1));
    let flush = subnormal::flushing();
    parts
        .into_par_iter()
        .zip(phi_parts)
        .zip(b_parts)
        .for_each(|(((ks, base), phi), b)| {
            // The calling thread's treatment of subnormals.
            let _flush = flush.then(FlushSubnormals::new);
            for k in ks {
                each(k, phi, b, (base.0, base.1));
            }
        });
}

/// The Hessian values of `kernels`, in parts as [`phi_b_in_parts`]:
/// `each(kernel, out, value)` writes a kernel's values of `out`, the slice
/// starting at global value `value`.
pub(crate) fn hessian_in_parts<K: KernelOffsets + Sync>(
    kernels: &[K],
    out: &mut [f64],
    each: impl Fn(&K, &mut [f64], usize) + Sync,
) {
    let parts = parallel_parts(kernels);
    if parts.is_empty() {
        for k in kernels {
            each(k, out, 0);
        }
        return;
    }
    let out_parts = split_at_bases(out, parts.iter().map(|p| p.1.2));
    let flush = subnormal::flushing();
    parts
        .into_par_iter()
        .zip(out_parts)
        .for_each(|((ks, base), out)| {
            let _flush = flush.then(FlushSubnormals::new);
            for k in ks {
                each(k, out, base.2);
            }
        });
}
