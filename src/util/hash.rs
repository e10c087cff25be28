//! A stable, non-cryptographic 128-bit hash for cache keys and content digests.

/// The 128-bit FNV-1a hash (offset basis `0x6c62272e07bb014262b821756295c58d`, prime
/// `2^88 + 0x13b`). Stable across platforms and releases, unlike `std`'s `DefaultHasher`;
/// not cryptographic, which a cache key does not need.
#[derive(Debug, Clone, Copy)]
pub struct Fnv128 {
    state: u128,
}

impl Default for Fnv128 {
    fn default() -> Self {
        Self::new()
    }
}

impl Fnv128 {
    const OFFSET: u128 = 0x6c62_272e_07bb_0142_62b8_2175_6295_c58d;
    const PRIME: u128 = 0x0000_0000_0100_0000_0000_0000_0000_013b;

    /// A hasher in its initial state.
    pub fn new() -> Self {
        Fnv128 {
            state: Self::OFFSET,
        }
    }

    /// Feeds `bytes`.
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.state ^= b as u128;
            self.state = self.state.wrapping_mul(Self::PRIME);
        }
    }

    /// The digest of everything written so far.
    pub fn finish(&self) -> u128 {
        self.state
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv128_reference_values() {
        // FNV-1a 128 of the empty string is the offset basis; of "a" the published value.
        assert_eq!(Fnv128::new().finish(), 0x6c62272e07bb014262b821756295c58d);
        let mut h = Fnv128::new();
        h.write(b"a");
        assert_eq!(h.finish(), 0xd228cb696f1a8caf78912b704e4a8964);
    }
}
