//! What the passes run on: the thread pool and its per-particle passes ([`pool`]), the pair
//! passes' split of the springs without atomics ([`scatter`]), the team whose members meet at
//! barriers ([`team`]), the crew of threads held ready for a tick ([`crew`]), big arrays on
//! huge pages ([`pages`]), and the machine's name for the figures ([`machine()`]).
//!
//! The ground floor of the core: it imports nothing of the solver but the packed spring record
//! (`solver::packed`), and every other room runs on it.

pub(crate) mod crew;
pub(crate) mod machine;
pub(crate) mod pages;
pub(crate) mod pool;
pub(crate) mod scatter;
pub(crate) mod team;

pub use machine::machine;
pub use pool::{MAX_THREADS, PARALLEL_MIN_SPRINGS, Threads};
pub use scatter::{Pair, PairPass, SpringBuffers, scatter_from};
