//! A minimal TensorBoard scalar event writer (the `tfevents` record format, hand-encoded).
//!
//! A file is a sequence of records: the payload length as a little-endian u64, the masked
//! CRC-32C of those 8 bytes, the payload, and the masked CRC-32C of the payload. The first
//! payload is an `Event` with `file_version = "brain.Event:2"`; each further one is an
//! `Event { wall_time, step, summary { value { tag, simple_value } ... } }`. Only the few
//! protobuf fields needed are encoded: `Event.wall_time` (1, double), `Event.step`
//! (2, int64), `Event.file_version` (3, string), `Event.summary` (5, message),
//! `Summary.value` (1, repeated message), `Value.tag` (1, string),
//! `Value.simple_value` (2, float).

/// The CRC-32C (Castagnoli) lookup table, reflected polynomial 0x82F63B78.
const CRC_TABLE: [u32; 256] = {
    let mut t = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0x82F6_3B78
            } else {
                c >> 1
            };
            k += 1;
        }
        t[i] = c;
        i += 1;
    }
    t
};

/// CRC-32C of `data` (as used by TFRecord; `crc32c(b"123456789") == 0xE3069283`).
pub fn crc32c(data: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in data {
        c = CRC_TABLE[((c ^ u32::from(b)) & 0xff) as usize] ^ (c >> 8);
    }
    !c
}

/// TFRecord's masked CRC: `((crc >> 15) | (crc << 17)) + 0xa282ead8` (wrapping).
pub fn masked_crc32c(data: &[u8]) -> u32 {
    let c = crc32c(data);
    c.rotate_right(15).wrapping_add(0xa282_ead8)
}

/// Frames `payload` as one TFRecord.
pub fn record(payload: &[u8]) -> Vec<u8> {
    let len = (payload.len() as u64).to_le_bytes();
    let mut out = Vec::with_capacity(payload.len() + 16);
    out.extend_from_slice(&len);
    out.extend_from_slice(&masked_crc32c(&len).to_le_bytes());
    out.extend_from_slice(payload);
    out.extend_from_slice(&masked_crc32c(payload).to_le_bytes());
    out
}

/// Error of a malformed record stream.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("tfevents record at byte {offset}: {message}")]
pub struct RecordError {
    /// Byte offset of the record.
    pub offset: usize,
    /// What is wrong.
    pub message: String,
}

/// Splits a record stream into payloads, checking both CRCs of every record.
pub fn read_records(bytes: &[u8]) -> Result<Vec<Vec<u8>>, RecordError> {
    let mut out = Vec::new();
    let mut i = 0;
    let u32_at =
        |p: usize| u32::from_le_bytes([bytes[p], bytes[p + 1], bytes[p + 2], bytes[p + 3]]);
    while i < bytes.len() {
        let bad = |message: &str| RecordError {
            offset: i,
            message: message.to_string(),
        };
        if bytes.len() - i < 12 {
            return Err(bad("truncated header"));
        }
        let mut lb = [0u8; 8];
        lb.copy_from_slice(&bytes[i..i + 8]);
        if u32_at(i + 8) != masked_crc32c(&lb) {
            return Err(bad("length CRC mismatch"));
        }
        let len = usize::try_from(u64::from_le_bytes(lb)).map_err(|_| bad("length overflow"))?;
        let start = i + 12;
        if bytes.len() - start < len.saturating_add(4) {
            return Err(bad("truncated payload"));
        }
        let payload = &bytes[start..start + len];
        if u32_at(start + len) != masked_crc32c(payload) {
            return Err(bad("payload CRC mismatch"));
        }
        out.push(payload.to_vec());
        i = start + len + 4;
    }
    Ok(out)
}

fn varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

fn len_delimited(out: &mut Vec<u8>, field: u32, bytes: &[u8]) {
    varint(out, u64::from(field << 3 | 2));
    varint(out, bytes.len() as u64);
    out.extend_from_slice(bytes);
}

/// The `Event` announcing the file format (`file_version = "brain.Event:2"`).
pub fn file_version_event(wall_time: f64) -> Vec<u8> {
    let mut e = vec![0x09];
    e.extend_from_slice(&wall_time.to_le_bytes());
    len_delimited(&mut e, 3, b"brain.Event:2");
    e
}

/// An `Event` holding `scalars` (tag, value) at `step`.
pub fn scalar_event(wall_time: f64, step: i64, scalars: &[(&str, f32)]) -> Vec<u8> {
    let mut summary = Vec::new();
    for (tag, v) in scalars {
        let mut value = Vec::new();
        len_delimited(&mut value, 1, tag.as_bytes());
        value.push(0x15);
        value.extend_from_slice(&v.to_le_bytes());
        len_delimited(&mut summary, 1, &value);
    }
    let mut e = vec![0x09];
    e.extend_from_slice(&wall_time.to_le_bytes());
    e.push(0x10);
    varint(&mut e, step as u64);
    len_delimited(&mut e, 5, &summary);
    e
}

/// A decoded scalar event.
#[derive(Debug, Clone, PartialEq)]
pub struct ScalarEvent {
    /// Seconds since the epoch.
    pub wall_time: f64,
    /// Global step.
    pub step: i64,
    /// (tag, value) pairs.
    pub values: Vec<(String, f32)>,
}

struct Reader<'a> {
    b: &'a [u8],
    i: usize,
}

impl Reader<'_> {
    fn varint(&mut self) -> Option<u64> {
        let mut v = 0u64;
        for shift in (0..64).step_by(7) {
            let byte = *self.b.get(self.i)?;
            self.i += 1;
            v |= u64::from(byte & 0x7f) << shift;
            if byte < 0x80 {
                return Some(v);
            }
        }
        None
    }
    fn take(&mut self, n: usize) -> Option<&[u8]> {
        let s = self.b.get(self.i..self.i.checked_add(n)?)?;
        self.i += n;
        Some(s)
    }
    fn done(&self) -> bool {
        self.i >= self.b.len()
    }
}

/// Decodes an `Event` payload written by [`scalar_event`] or [`file_version_event`]
/// (`None` for anything it does not understand). Used to check files in tests and tools.
pub fn decode_event(payload: &[u8]) -> Option<ScalarEvent> {
    let mut r = Reader { b: payload, i: 0 };
    let mut ev = ScalarEvent {
        wall_time: 0.0,
        step: 0,
        values: Vec::new(),
    };
    while !r.done() {
        let key = r.varint()?;
        match key {
            0x09 => ev.wall_time = f64::from_le_bytes(r.take(8)?.try_into().ok()?),
            0x10 => ev.step = r.varint()? as i64,
            0x1a => {
                let n = r.varint()? as usize;
                r.take(n)?;
            }
            0x2a => {
                let n = r.varint()? as usize;
                let mut s = Reader {
                    b: r.take(n)?,
                    i: 0,
                };
                while !s.done() {
                    if s.varint()? != 0x0a {
                        return None;
                    }
                    let n = s.varint()? as usize;
                    let mut v = Reader {
                        b: s.take(n)?,
                        i: 0,
                    };
                    let (mut tag, mut val) = (String::new(), 0f32);
                    while !v.done() {
                        match v.varint()? {
                            0x0a => {
                                let n = v.varint()? as usize;
                                tag = String::from_utf8(v.take(n)?.to_vec()).ok()?;
                            }
                            0x15 => val = f32::from_le_bytes(v.take(4)?.try_into().ok()?),
                            _ => return None,
                        }
                    }
                    ev.values.push((tag, val));
                }
            }
            _ => return None,
        }
    }
    Some(ev)
}

/// The scalars of one event: (tag, value) pairs.
pub type Scalars<'a> = Vec<(&'a str, f32)>;

/// The bytes of a whole event file: the version record, then one record per
/// (wall_time, step, scalars) entry.
pub fn event_file(t0: f64, entries: &[(f64, i64, Scalars<'_>)]) -> Vec<u8> {
    let mut out = record(&file_version_event(t0));
    for (wall, step, scalars) in entries {
        out.extend_from_slice(&record(&scalar_event(*wall, *step, scalars)));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32c_known_vectors() {
        assert_eq!(crc32c(b"123456789"), 0xE306_9283);
        assert_eq!(crc32c(b""), 0);
        // RFC 3720 B.4: 32 bytes of zeros.
        assert_eq!(crc32c(&[0u8; 32]), 0x8A91_36AA);
        // ((0xE3069283 >> 15) | (0xE3069283 << 17)) + 0xa282ead8, worked by hand.
        assert_eq!(masked_crc32c(b"123456789"), 0xC78A_B0E5);
    }

    #[test]
    fn record_framing_and_crc_checks() {
        let r = record(b"abc");
        assert_eq!(r.len(), 8 + 4 + 3 + 4);
        assert_eq!(&r[..8], &3u64.to_le_bytes());
        assert_eq!(&r[12..15], b"abc");
        let two = [r.clone(), record(b"")].concat();
        assert_eq!(read_records(&two).unwrap(), vec![b"abc".to_vec(), vec![]]);
        let mut bad = r.clone();
        bad[13] ^= 1;
        assert!(read_records(&bad)
            .unwrap_err()
            .message
            .contains("payload CRC"));
        let mut bad = r.clone();
        bad[0] ^= 1;
        assert!(read_records(&bad)
            .unwrap_err()
            .message
            .contains("length CRC"));
        assert!(read_records(&r[..r.len() - 1]).is_err());
    }

    #[test]
    fn scalar_event_encoding_by_hand() {
        let e = scalar_event(1.5, 300, &[("a", 2.0)]);
        let mut want = vec![0x09];
        want.extend_from_slice(&1.5f64.to_le_bytes());
        // step 300 = varint ac 02
        want.extend_from_slice(&[0x10, 0xac, 0x02]);
        // summary (len 10) { value (len 8) { tag "a", simple_value 2.0 } }
        want.extend_from_slice(&[0x2a, 10, 0x0a, 8, 0x0a, 1, b'a', 0x15]);
        want.extend_from_slice(&2.0f32.to_le_bytes());
        assert_eq!(e, want);
        let d = decode_event(&e).unwrap();
        assert_eq!(d.step, 300);
        assert_eq!(d.values, vec![("a".to_string(), 2.0)]);
        let v = decode_event(&file_version_event(2.0)).unwrap();
        assert!(v.values.is_empty() && v.wall_time == 2.0);
        assert!(decode_event(&[0xff]).is_none());
    }

    #[test]
    fn event_file_reads_back() {
        let bytes = event_file(10.0, &[(11.0, 1, vec![("x", 0.5), ("y", -1.0)])]);
        let recs = read_records(&bytes).unwrap();
        assert_eq!(recs.len(), 2);
        let e = decode_event(&recs[1]).unwrap();
        assert_eq!((e.wall_time, e.step, e.values.len()), (11.0, 1, 2));
    }
}
