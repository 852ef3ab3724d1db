//! Image output shared by the host and the firmware: the digest and the PPM header.

/// FNV-1a (64 bits) of `bytes`: the digest the tests pin and the firmware prints.
#[must_use]
pub fn fnv1a(bytes: &[u8]) -> u64 {
    use core::hash::Hasher;
    let mut h = fnv::FnvHasher::default();
    h.write(bytes);
    h.finish()
}

/// Writes the header of a binary PPM (`P6`) image of `width × height` RGB8 pixels into `out`
/// and returns its length (at most 27 bytes), or `None` when `out` is too short. The host and
/// the firmware write the same bytes.
pub fn ppm_header(width: u32, height: u32, out: &mut [u8]) -> Option<usize> {
    let mut n = 0;
    let mut put = |b: u8| -> Option<()> {
        *out.get_mut(n)? = b;
        n += 1;
        Some(())
    };
    for &b in b"P6\n" {
        put(b)?;
    }
    for (v, end) in [(width, b' '), (height, b'\n'), (255, b'\n')] {
        let mut digits = [0u8; 10];
        let (mut v, mut k) = (v, 0);
        loop {
            digits[k] = b'0' + (v % 10) as u8;
            k += 1;
            v /= 10;
            if v == 0 {
                break;
            }
        }
        for &dg in digits[..k].iter().rev() {
            put(dg)?;
        }
        put(end)?;
    }
    Some(n)
}
