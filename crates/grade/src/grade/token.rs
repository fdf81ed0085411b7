//! Random names: the session token a student's program must echo, and the tags of temporary
//! files and folders. A leaf of the grader: the builder, the session and the report use it.

use std::io::Read;

use springlab_homework::wire::TOKEN_LEN;

/// 16 random bytes for a session token: the system's random source, or, where there is none,
/// std's randomly keyed hasher.
pub(crate) fn random_token() -> [u8; TOKEN_LEN] {
    let mut token = [0u8; TOKEN_LEN];
    let from_os = std::fs::File::open("/dev/urandom").and_then(|mut f| f.read_exact(&mut token));
    if from_os.is_err() {
        use std::hash::{BuildHasher, Hasher};
        for (i, chunk) in token.chunks_mut(8).enumerate() {
            let mut h = std::collections::hash_map::RandomState::new().build_hasher();
            h.write_usize(i);
            h.write_u128(
                std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map_or(0, |d| d.as_nanos()),
            );
            chunk.copy_from_slice(&h.finish().to_le_bytes());
        }
    }
    token
}

/// 12 random hex digits, for names of temporary files and folders.
pub(crate) fn random_tag() -> String {
    random_token()[..6]
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}
