//! Progress reporting hooks: long phases (photon passes, the camera pass, progressive passes)
//! report through [`Progress`]; the CLI wires it to progress bars, tests and tools pass
//! [`NoProgress`]. A leaf: it imports nothing from the crate.

/// Where a render reports how far it has got.
pub trait Progress: Sync {
    /// A phase starts with `total` units of work.
    fn start(&self, phase: &str, total: u64);
    /// `n` more units are done.
    fn advance(&self, n: u64);
    /// A status line beside the bar (passes, time left).
    fn message(&self, _text: &str) {}
    /// The phase is over.
    fn finish(&self);
}

/// Reports nothing.
pub struct NoProgress;

impl Progress for NoProgress {
    fn start(&self, _: &str, _: u64) {}
    fn advance(&self, _: u64) {}
    fn finish(&self) {}
}
