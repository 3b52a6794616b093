//! Per-cell random streams: every (cell, repeat) gets its own ChaCha stream whose 256-bit seed is
//! SHA-256("somnurbs/seed/v1", master seed, cell key). Results therefore do not depend on thread
//! count, cell order, or which other cells run, and one cell can be re-run alone.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use sha2::{Digest, Sha256};

/// The part of a cell's log key that names its place (and so its stream): the key itself, or
/// for a key `PLACE#IDENTITY` ([`identity_key`]) the part before its 16-digit identity.
pub(crate) fn place_of(key: &str) -> &str {
    match key.rsplit_once('#') {
        Some((place, id)) if id.len() == 16 && id.bytes().all(|b| b.is_ascii_hexdigit()) => place,
        _ => key,
    }
}

/// The log key of a cell known by what it computes: `PLACE#` and the first 8 bytes (hex) of
/// SHA-256 over `parts` (the cell's inputs, each length-prefixed). Its stream stays that of
/// `place` ([`place_of`]), so the variants of one place share their random numbers.
pub(crate) fn identity_key(place: &str, parts: &[&[u8]]) -> String {
    let mut h = Sha256::new();
    h.update(b"somnurbs/cell/v1\0");
    h.update((place.len() as u64).to_le_bytes());
    h.update(place.as_bytes());
    for p in parts {
        h.update((p.len() as u64).to_le_bytes());
        h.update(p);
    }
    format!("{place}#{}", hex::encode(&h.finalize()[..8]))
}

/// The 32-byte seed of a cell's stream.
pub(crate) fn cell_seed(master_seed: u64, cell_key: &str) -> [u8; 32] {
    let mut h = Sha256::new();
    h.update(b"somnurbs/seed/v1\0");
    h.update(master_seed.to_le_bytes());
    h.update(cell_key.as_bytes());
    h.finalize().into()
}

/// The cell's random stream.
pub fn cell_rng(master_seed: u64, cell_key: &str) -> ChaCha8Rng {
    ChaCha8Rng::from_seed(cell_seed(master_seed, cell_key))
}

/// Short hex form of a cell's seed for listings and CSVs (first 8 bytes).
pub fn seed_hex(master_seed: u64, cell_key: &str) -> String {
    hex::encode(&cell_seed(master_seed, cell_key)[..8])
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::RngCore;

    #[test]
    fn streams_differ_by_key_and_master_and_repeat_exactly() {
        let a = cell_rng(1, "som/cube/dnsom/10x10/r0").next_u64();
        assert_eq!(a, cell_rng(1, "som/cube/dnsom/10x10/r0").next_u64());
        assert_ne!(a, cell_rng(2, "som/cube/dnsom/10x10/r0").next_u64());
        assert_ne!(a, cell_rng(1, "som/cube/dnsom/10x10/r1").next_u64());
        assert_eq!(seed_hex(1, "k").len(), 16);
    }

    #[test]
    fn an_identity_keeps_its_places_stream_and_differs_by_its_inputs() {
        let a = identity_key("optim/cube/20x20/6x6/uniform/de/r0", &[b"f=0.3"]);
        let b = identity_key("optim/cube/20x20/6x6/uniform/de/r0", &[b"f=0.8"]);
        assert_ne!(a, b);
        assert_eq!(place_of(&a), "optim/cube/20x20/6x6/uniform/de/r0");
        assert_eq!(place_of(&a), place_of(&b));
        // Length prefixes: moving a byte between parts is another identity.
        assert_ne!(identity_key("p", &[b"ab", b"c"]), identity_key("p", &[b"a", b"bc"]));
        // A key without an identity, or with a `#` of its own, is its own place.
        assert_eq!(place_of("som/cube/dnsom/10x10/r0"), "som/cube/dnsom/10x10/r0");
        assert_eq!(place_of("fit/my#scan/r0"), "fit/my#scan/r0");
    }
}
