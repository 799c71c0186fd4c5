//! Joint kernels in chunks for rayon: the planar revolute and the spatial
//! spherical kernels of long chains are evaluated in parallel parts that
//! write disjoint rows and values.

/// The fewest joints in one parallel chunk.
pub(crate) const PARALLEL_CHUNK: usize = 2048;

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
