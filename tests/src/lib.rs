//! Holder crate for the cross-crate tests in `tests/tests/`, and what several of them share.

/// A xorshift64 generator: the random programs and operands of the tests, reproducible
/// from a seed.
pub struct XorShift(pub u64);

impl XorShift {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    /// A value in `0..n`.
    pub fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}
