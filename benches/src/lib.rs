//! Criterion benchmarks of mstar (`cargo bench -p mstar-benches`, or
//! `cargo xtask bench` for the summary table). The benchmarks live in
//! `benches/`; this library is empty.
