//! The byte layout of a saved fluid state, shared by both methods: one line of JSON header,
//! then the state's f64 values, little-endian, in the order the method writes them.

/// Header line and body of a saved state; `None` if there is no header line.
pub fn split(state: &[u8]) -> Option<(&[u8], &[u8])> {
    let nl = state.iter().position(|&b| b == b'\n')?;
    Some((&state[..nl], &state[nl + 1..]))
}

/// The header line followed by `values`.
pub fn join(header: &[u8], values: impl ExactSizeIterator<Item = f64>) -> Vec<u8> {
    let mut out = Vec::with_capacity(header.len() + 1 + 8 * values.len());
    out.extend_from_slice(header);
    out.push(b'\n');
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

/// The f64 values of a body (a trailing partial value is ignored; callers check the length).
pub fn values(body: &[u8]) -> impl Iterator<Item = f64> + '_ {
    body.chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().unwrap_or([0; 8])))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_survive_bit_for_bit() {
        let v = [1.0 / 3.0, -0.0, f64::MIN_POSITIVE, 1e300];
        let saved = join(b"{\"a\":1}", v.iter().copied());
        let (h, body) = split(&saved).unwrap();
        assert_eq!(h, b"{\"a\":1}");
        let back: Vec<u64> = values(body).map(f64::to_bits).collect();
        assert_eq!(back, v.map(f64::to_bits));
        assert!(split(b"no header").is_none());
    }
}
