use et_learn::npz::*;
use nalgebra::DMatrix;

fn sample() -> Vec<u8> {
    let mut w = Writer::new();
    w.matrix(
        "x",
        &DMatrix::from_fn(3, 2, |i, j| i as f64 + 10.0 * j as f64),
    );
    w.u16s("label", &[0, 7, 65535]);
    w.pairs("p", &[[1.5, -2.0], [3.0, 4.0]]);
    w.f64s("empty", &[]);
    w.text("config", "{\"a\": \"µ\"}");
    w.finish().unwrap()
}

#[test]
fn what_is_written_reads_back() {
    let z = Npz::read(sample()).unwrap();
    assert_eq!(
        z.names().collect::<Vec<_>>(),
        ["x", "label", "p", "empty", "config"]
    );
    let x = z.matrix("x").unwrap();
    assert_eq!(x, DMatrix::from_fn(3, 2, |i, j| i as f64 + 10.0 * j as f64));
    assert_eq!(z.whole("label").unwrap(), [0, 7, 65535]);
    assert_eq!(
        z.matrix("p").unwrap(),
        DMatrix::from_row_slice(2, 2, &[1.5, -2.0, 3.0, 4.0])
    );
    assert!(z.vector("empty").unwrap().is_empty());
    assert_eq!(z.text("config").unwrap(), "{\"a\": \"µ\"}");
    assert!(z.matrix("label").is_err(), "1-d is not a matrix");
    assert!(z.text("x").is_err());
    // Said with the names the archive holds (it was "missing").
    let e = z.vector("nope").unwrap_err();
    assert!(matches!(e.fault, NpzFault::Missing { .. }));
    assert!(
        e.to_string()
            .contains("not in the archive, which holds x, "),
        "{e}"
    );
}

#[test]
fn every_entry_is_aligned_and_its_crc_right() {
    let bytes = sample();
    let z = Npz::read(bytes.clone()).unwrap();
    for (name, range) in z.entries() {
        let npy = &bytes[range.clone()];
        let header = usize::from(u16::from_le_bytes([npy[8], npy[9]]));
        assert_eq!((10 + header) % 64, 0, "{name}: numpy aligns data to 64");
        // The local header's CRC (offset 14) is of the entry's bytes.
        let local = range.start - 30 - name.len() - 4;
        assert_eq!(
            u32::from_le_bytes(bytes[local + 14..local + 18].try_into().unwrap()),
            crc32fast::hash(npy)
        );
    }
}

/// A value's flipped bit inside a stored entry is caught by the entry's checksum (it was read
/// as another value).
#[test]
fn an_entry_failing_its_checksum_is_refused() {
    let bytes = sample();
    let z = Npz::read(bytes.clone()).unwrap();
    let (name, range) = z.entries()[0].clone();
    let mut b = bytes.clone();
    b[range.end - 1] ^= 0x01;
    let e = Npz::read(b).unwrap_err();
    assert_eq!(
        (e.fault.clone(), e.array.as_deref()),
        (NpzFault::Checksum, Some(name.as_str()))
    );
    assert!(e.to_string().contains("checksum"), "{e}");
}

#[test]
fn broken_archives_are_errors_not_panics() {
    let bytes = sample();
    for cut in [0, 4, 30, 100, bytes.len() / 2, bytes.len() - 1] {
        let mut b = bytes.clone();
        b.truncate(cut);
        if let Ok(z) = Npz::read(b) {
            let _ = z.matrix("x");
        }
    }
    for i in (0..bytes.len()).step_by(7) {
        let mut b = bytes.clone();
        b[i] ^= 0xA5;
        if let Ok(z) = Npz::read(b) {
            for n in ["x", "label", "p", "empty", "config"] {
                let _ = (z.matrix(n), z.whole(n), z.text(n));
            }
        }
    }
    // A descr whose first character is several bytes long (the fuzzer's byte-order mark
    // inserted before '<f8'): refused, where splitting at byte 1 panicked.
    let npy = et_learn::npz::npy_of_matrix(&nalgebra::DMatrix::from_element(2, 3, 1.0));
    let at = npy.windows(5).position(|w| w == b"'<f8'").unwrap() + 1;
    let mut marked = npy[..at].to_vec();
    marked.extend("\u{feff}".as_bytes());
    marked.extend(&npy[at..]);
    let e = Npz::from_npy(marked).matrix("array").unwrap_err();
    assert!(e.to_string().contains("f8"), "{e}");
    let mut b = bytes.clone();
    let central = bytes.windows(4).position(|w| w == b"PK\x01\x02").unwrap();
    b[central + 10] = 12; // the first entry's method: bzip2
    let e = Npz::read(b).unwrap_err();
    assert_eq!(e.fault, NpzFault::Method(12));
    assert!(e.to_string().contains("savez_compressed"), "{e}");
}

/// What `numpy.savez_compressed` writes (deflated entries, zip64 local headers) reads as
/// `numpy.load` reads it, a big-endian array included; a damaged deflated entry, one that
/// inflates to another size than stated, and stated sizes past the data files' limit are
/// refused by name.
#[test]
fn savez_compressed_archives_read_as_numpy_reads_them() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/numpy/savez-compressed.npz");
    let bytes = std::fs::read(path).unwrap();
    let z = Npz::read(bytes.clone()).unwrap();
    let x = z.matrix("x").unwrap();
    assert_eq!((x.nrows(), x.ncols()), (2, 3));
    assert_eq!(x[(1, 0)], 0.75); // np.arange(6.0).reshape(2, 3) / 4, row-major
    assert_eq!(z.whole("label").unwrap(), [3, 1]); // stored '>i4'
    assert_eq!(z.text("name").unwrap(), "tank");

    let central = bytes.windows(4).position(|w| w == b"PK\x01\x02").unwrap();
    let local = bytes.windows(4).position(|w| w == b"PK\x03\x04").unwrap();
    let data_at = local + 30 + usize::from(bytes[local + 26]) + usize::from(bytes[local + 28]);
    let mut damaged = bytes.clone();
    damaged[data_at + 2] ^= 0x55;
    let e = Npz::read(damaged).unwrap_err();
    assert!(
        matches!(e.fault, NpzFault::Inflate | NpzFault::Checksum),
        "{e}"
    );
    assert!(e.to_string().contains("damaged"), "{e}");
    // The first entry's stated size one more than it inflates to; then 2^31 bytes.
    let size = u32::from_le_bytes(bytes[central + 24..central + 28].try_into().unwrap());
    let mut longer = bytes.clone();
    longer[central + 24..central + 28].copy_from_slice(&(size + 1).to_le_bytes());
    assert_eq!(Npz::read(longer).unwrap_err().fault, NpzFault::Inflate);
    let mut bomb = bytes;
    bomb[central + 24..central + 28].copy_from_slice(&(1u32 << 31).to_le_bytes());
    let e = Npz::read(bomb).unwrap_err();
    assert!(matches!(e.fault, NpzFault::Inflates(_)), "{e}");
}

/// Two entries of one name (a zip may hold them; numpy reads the last): refused by name.
#[test]
fn an_array_stored_twice_is_refused() {
    let mut w = Writer::new();
    w.f64s("x", &[1.0, 2.0]);
    w.f64s("y", &[0.0]);
    w.f64s("x", &[3.0, 4.0]);
    let e = Npz::read(w.finish().unwrap()).unwrap_err().to_string();
    assert!(e.contains("stored twice"), "{e}");
}
