//! A [`WarmStart`] on disk, so that an optimization resumed in another process starts its GMRES
//! from the last designs' solutions rather than from zero. Little-endian binary: the magic
//! `GKWARM01`, the unknowns per solution, the designs to keep, then the tables' and the reverse
//! sweeps' designs, each as its reduced frequencies with their columns of single-precision
//! complex values. A file that is not one, is cut short or holds a non-finite value is refused
//! with the reason: a guess is never trusted blindly, only started from.

use super::{KeptDesign, WarmStart};
use num_complex::Complex32;
use std::io::{self, Read, Write};

const MAGIC: &[u8; 8] = b"GKWARM01";

/// Largest count any length field may claim before its data are read (a corrupt length must not
/// ask for terabytes): 2^40 values.
const MAX_COUNT: u64 = 1 << 40;

fn put_u64(w: &mut impl Write, v: u64) -> io::Result<()> {
    w.write_all(&v.to_le_bytes())
}

fn get_u64(r: &mut impl Read) -> io::Result<u64> {
    let mut b = [0u8; 8];
    r.read_exact(&mut b)?;
    Ok(u64::from_le_bytes(b))
}

fn count(r: &mut impl Read, what: &str) -> io::Result<usize> {
    let v = get_u64(r)?;
    if v > MAX_COUNT {
        return Err(bad(format!("{what} = {v} is not a plausible count")));
    }
    Ok(v as usize)
}

fn bad(reason: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, reason)
}

fn write_designs(w: &mut impl Write, designs: &[KeptDesign]) -> io::Result<()> {
    put_u64(w, designs.len() as u64)?;
    for design in designs {
        put_u64(w, design.len() as u64)?;
        for (k, columns) in design {
            w.write_all(&k.to_le_bytes())?;
            put_u64(w, columns.len() as u64)?;
            for x in columns {
                put_u64(w, x.len() as u64)?;
                for v in x {
                    w.write_all(&v.re.to_le_bytes())?;
                    w.write_all(&v.im.to_le_bytes())?;
                }
            }
        }
    }
    Ok(())
}

fn read_designs(r: &mut impl Read, n: usize) -> io::Result<Vec<KeptDesign>> {
    let designs = count(r, "designs")?;
    let mut out = Vec::with_capacity(designs.min(64));
    for _ in 0..designs {
        let frequencies = count(r, "reduced frequencies")?;
        let mut design: KeptDesign = Vec::with_capacity(frequencies.min(1024));
        for _ in 0..frequencies {
            let mut b = [0u8; 8];
            r.read_exact(&mut b)?;
            let k = f64::from_le_bytes(b);
            if !k.is_finite() {
                return Err(bad(format!("reduced frequency {k} is not finite")));
            }
            let columns = count(r, "columns")?;
            let mut solved = Vec::with_capacity(columns.min(1024));
            for _ in 0..columns {
                let len = count(r, "solution length")?;
                if len != n {
                    return Err(bad(format!(
                        "a solution of {len} values where the file's header says {n}"
                    )));
                }
                let mut bytes = vec![0u8; 8 * len];
                r.read_exact(&mut bytes)?;
                let x: Vec<Complex32> = bytes
                    .chunks_exact(8)
                    .map(|c| {
                        Complex32::new(
                            f32::from_le_bytes([c[0], c[1], c[2], c[3]]),
                            f32::from_le_bytes([c[4], c[5], c[6], c[7]]),
                        )
                    })
                    .collect();
                if x.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())) {
                    return Err(bad(format!("a non-finite value in a solution at k = {k}")));
                }
                solved.push(x);
            }
            design.push((k, solved));
        }
        out.push(design);
    }
    Ok(out)
}

impl WarmStart {
    /// The solutions' bytes on disk (8 a complex value: two f32), without the few length fields.
    pub fn file_bytes(&self) -> u64 {
        let values: usize = self
            .tables
            .iter()
            .chain(&self.adjoints)
            .flat_map(|d| d.iter())
            .flat_map(|(_, c)| c.iter())
            .map(|x| x.len())
            .sum();
        8 * values as u64
    }

    /// Unknowns of each kept solution (cells × 5); 0 while nothing is kept.
    pub fn unknowns(&self) -> usize {
        self.n
    }

    /// Writes the kept designs (tables and reverse sweeps) and how many designs to keep.
    pub fn write_to(&self, w: &mut impl Write) -> io::Result<()> {
        w.write_all(MAGIC)?;
        put_u64(w, self.n as u64)?;
        put_u64(w, self.designs as u64)?;
        write_designs(w, &self.tables)?;
        write_designs(w, &self.adjoints)?;
        w.flush()
    }

    /// A store read back from what [`WarmStart::write_to`] wrote; the iteration counters start
    /// at zero (they describe this process's solves).
    pub fn read_from(r: &mut impl Read) -> io::Result<WarmStart> {
        let mut magic = [0u8; 8];
        r.read_exact(&mut magic)?;
        if &magic != MAGIC {
            return Err(bad("not a gustkit warm-start file".into()));
        }
        let n = count(r, "unknowns")?;
        let designs = count(r, "designs to keep")?.max(1);
        let tables = read_designs(r, n)?;
        let adjoints = read_designs(r, n)?;
        let mut rest = [0u8; 1];
        if r.read(&mut rest)? != 0 {
            return Err(bad("data after the end of the store".into()));
        }
        Ok(WarmStart {
            n,
            tables,
            adjoints,
            designs,
            ..Default::default()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn store() -> WarmStart {
        let x = |s: f32| -> Vec<Complex32> {
            (0..6)
                .map(|i| Complex32::new(s * i as f32, -s / (1.0 + i as f32)))
                .collect()
        };
        WarmStart {
            n: 6,
            tables: vec![
                vec![(0.0, vec![x(1.0), x(2.0)]), (0.5, vec![x(3.0), x(4.0)])],
                vec![(0.0, vec![x(5.0), x(6.0)])],
            ],
            adjoints: vec![vec![(0.5, vec![x(7.0)])]],
            designs: 2,
            last_iterations: 9,
            ..Default::default()
        }
    }

    /// What is written is read back bit for bit (tables, adjoints, the designs to keep; the
    /// counters, which describe one process, start at zero), and the size is what
    /// `file_bytes` says plus the header and length fields.
    #[test]
    fn round_trip_is_exact() {
        let s = store();
        let mut bytes = Vec::new();
        s.write_to(&mut bytes).unwrap();
        let r = WarmStart::read_from(&mut bytes.as_slice()).unwrap();
        assert_eq!(r.n, 6);
        assert_eq!(r.designs, 2);
        assert_eq!(r.tables, s.tables);
        assert_eq!(r.adjoints, s.adjoints);
        assert_eq!(r.last_iterations, 0);
        // 7 solutions of 6 values: 336 bytes of data
        assert_eq!(s.file_bytes(), 336);
        assert!(bytes.len() as u64 > s.file_bytes());
    }

    /// Refused with the reason: another file, a file cut short, a non-finite value, a solution
    /// whose length contradicts the header, and trailing data.
    #[test]
    fn damaged_files_are_refused() {
        let mut bytes = Vec::new();
        store().write_to(&mut bytes).unwrap();
        let read = |b: &[u8]| WarmStart::read_from(&mut &b[..]).map(|_| ()).unwrap_err();
        assert!(read(b"{\"not\": 1}xxxxxxx")
            .to_string()
            .contains("not a gustkit warm-start file"));
        assert_eq!(
            read(&bytes[..bytes.len() - 3]).kind(),
            io::ErrorKind::UnexpectedEof
        );
        let mut extra = bytes.clone();
        extra.push(0);
        assert!(read(&extra).to_string().contains("after the end"));
        // the first solution value's real part (after magic, n, designs, 1 design count, k count,
        // k, column count, length: 8 × 8 bytes) set to NaN
        let mut nan = bytes.clone();
        nan[64..68].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(read(&nan).to_string().contains("non-finite"));
        // the header claims 5 unknowns a solution
        let mut short = bytes.clone();
        short[8..16].copy_from_slice(&5u64.to_le_bytes());
        assert!(read(&short).to_string().contains("header says 5"));
    }
}
