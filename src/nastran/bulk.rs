//! The bulk data cards gustkit reads, typed, in the model's own units (field names as the MSC
//! Nastran Quick Reference Guide gives them; NASTRAN-95 decks use the same layouts).
//!
//! [`BulkData::from_cards`] sorts a deck's cards by kind, refuses duplicate ids and unsupported
//! cards (naming card, line and what to do), and names in one warning line the cards it reads
//! but does not use.

use super::deck::Card;
use super::field::Value;
use super::NastranError;
use std::collections::BTreeMap;

type R<T> = Result<T, NastranError>;

/// A grid point: location in coordinate system `cp`, displacement system `cd`, permanent
/// single-point constraints `ps` (components 1–6).
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    pub id: u32,
    pub cp: u32,
    pub x: [f64; 3],
    pub cd: u32,
    pub ps: Vec<u8>,
}

/// A rectangular coordinate system from three points: origin A, a point B on the z axis and a
/// point C in the x–z plane, given in system `rid`.
#[derive(Clone, Debug, PartialEq)]
pub struct Cord2r {
    pub id: u32,
    pub rid: u32,
    pub a: [f64; 3],
    pub b: [f64; 3],
    pub c: [f64; 3],
}

/// A lumped mass on a grid: CONM2's mass, offset and inertia (in system `cid`), or CONM1's
/// full symmetric 6 × 6 matrix (lower triangle, row by row).
#[derive(Clone, Debug, PartialEq)]
pub enum Conm {
    Conm2 {
        id: u32,
        grid: u32,
        cid: i64,
        mass: f64,
        offset: [f64; 3],
        /// I11, I21, I22, I31, I32, I33.
        inertia: [f64; 6],
    },
    Conm1 {
        id: u32,
        grid: u32,
        cid: u32,
        /// M11, M21, M22, M31, … M66 (21 terms).
        lower: [f64; 21],
    },
}

/// A scalar spring (CELAS2) or mass (CMASS2) between two grid components (the second may be
/// ground: grid 0).
#[derive(Clone, Debug, PartialEq)]
pub struct Scalar {
    pub id: u32,
    pub value: f64,
    pub g1: u32,
    pub c1: u8,
    pub g2: u32,
    pub c2: u8,
    /// CELAS2's damping coefficient GE.
    pub ge: f64,
}

/// The orientation of a bar or beam: a vector in the displacement system of end A, or a grid.
#[derive(Clone, Debug, PartialEq)]
pub enum Orientation {
    Vector([f64; 3]),
    Grid(u32),
}

/// A bar or beam element (CBAR, CBEAM): ends, orientation, pin flags, offsets.
#[derive(Clone, Debug, PartialEq)]
pub struct Bar {
    pub id: u32,
    pub pid: u32,
    pub ga: u32,
    pub gb: u32,
    pub orientation: Orientation,
    pub pa: Vec<u8>,
    pub pb: Vec<u8>,
    pub wa: [f64; 3],
    pub wb: [f64; 3],
    pub beam: bool,
}

/// A bar or (constant-section) beam property: area, moments of inertia, torsion constant,
/// non-structural mass per length, shear factors.
#[derive(Clone, Debug, PartialEq)]
pub struct BarProperty {
    pub id: u32,
    pub mid: u32,
    pub area: f64,
    pub i1: f64,
    pub i2: f64,
    pub i12: f64,
    pub j: f64,
    pub nsm: f64,
    pub k1: Option<f64>,
    pub k2: Option<f64>,
}

/// A shell element (CQUAD4 with 4 grids, CTRIA3 with 3): property, material angle or system,
/// offset, corner thicknesses.
#[derive(Clone, Debug, PartialEq)]
pub struct Shell {
    pub id: u32,
    pub pid: u32,
    pub grids: Vec<u32>,
    pub theta: f64,
    pub mcid: Option<u32>,
    pub zoffs: f64,
    pub corner_t: Vec<Option<f64>>,
}

/// A shell property: membrane, bending, shear and coupling materials, thickness, bending
/// stiffness ratio 12I/T³, transverse shear ratio, non-structural mass per area.
#[derive(Clone, Debug, PartialEq)]
pub struct Pshell {
    pub id: u32,
    pub mid1: Option<u32>,
    pub t: f64,
    pub mid2: Option<u32>,
    pub bending_ratio: f64,
    pub mid3: Option<u32>,
    pub ts_t: f64,
    pub nsm: f64,
}

/// An isotropic (MAT1) or orthotropic shell (MAT8) material.
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    Mat1 {
        id: u32,
        e: f64,
        g: f64,
        nu: f64,
        rho: f64,
        ge: f64,
    },
    Mat8 {
        id: u32,
        e1: f64,
        e2: f64,
        nu12: f64,
        g12: f64,
        g1z: f64,
        g2z: f64,
        rho: f64,
        ge: f64,
    },
}

/// A general element in stiffness (K) or flexibility (Z) form: independent components `ui`,
/// dependent `ud`, the lower triangle of K or Z (row by row) and S (row by row, ui × ud).
#[derive(Clone, Debug, PartialEq)]
pub struct Genel {
    pub id: u32,
    pub ui: Vec<(u32, u8)>,
    pub ud: Vec<(u32, u8)>,
    pub flexibility: bool,
    pub matrix: Vec<f64>,
    pub s: Vec<f64>,
}

/// A rigid element: RBE2 (grid `gn`'s components `cm` drive the dependent grids) or RBAR
/// (independent and dependent components at both ends).
#[derive(Clone, Debug, PartialEq)]
pub enum Rigid {
    Rbe2 {
        id: u32,
        gn: u32,
        cm: Vec<u8>,
        gm: Vec<u32>,
    },
    Rbar {
        id: u32,
        ga: u32,
        gb: u32,
        cna: Vec<u8>,
        cnb: Vec<u8>,
        cma: Vec<u8>,
        cmb: Vec<u8>,
    },
}

/// A multipoint constraint equation Σ A_i u(G_i, C_i) = 0; the first term is the dependent one.
#[derive(Clone, Debug, PartialEq)]
pub struct Mpc {
    pub sid: u32,
    pub terms: Vec<(u32, u8, f64)>,
    pub source: super::Source,
}

/// Single-point constraints of set `sid`: components of grids, with enforced values (SPC) or
/// zero (SPC1).
#[derive(Clone, Debug, PartialEq)]
pub struct Spc {
    pub sid: u32,
    pub grid: u32,
    pub components: Vec<u8>,
    pub value: f64,
    pub source: super::Source,
}

/// A real eigenvalue method: EIGR (method, frequency range, number of roots) or EIGRL.
#[derive(Clone, Debug, PartialEq)]
pub struct Eigr {
    pub sid: u32,
    pub method: String,
    pub f1: Option<f64>,
    pub f2: Option<f64>,
    pub nd: Option<u32>,
    pub norm: String,
}

/// A lifting surface panel (CAERO1): property, coordinate system, spanwise and chordwise
/// divisions (counts or AEFACT lists), leading-edge points 1 and 4 and chords.
#[derive(Clone, Debug, PartialEq)]
pub struct Caero1 {
    pub id: u32,
    pub pid: u32,
    pub cp: u32,
    pub nspan: Option<u32>,
    pub nchord: Option<u32>,
    pub lspan: Option<u32>,
    pub lchord: Option<u32>,
    pub igid: i64,
    pub p1: [f64; 3],
    pub x12: f64,
    pub p4: [f64; 3],
    pub x43: f64,
}

/// A spline from structural grids (a SET1) to aerodynamic boxes of one CAERO: SPLINE1
/// (infinite plate), SPLINE2 (beam), SPLINE4 (thin plate, boxes by an AELIST).
#[derive(Clone, Debug, PartialEq)]
pub struct Spline {
    pub id: u32,
    pub kind: SplineKind,
    pub caero: u32,
    /// First and last box (SPLINE1, SPLINE2), or None (SPLINE4 names them by `aelist`).
    pub boxes: Option<(u32, u32)>,
    pub aelist: Option<u32>,
    pub setg: u32,
    pub dz: f64,
    /// SPLINE2: torsional flexibility, axis system, rotational attachment flexibilities.
    pub dtor: f64,
    pub cid: u32,
    pub dthx: f64,
    pub dthy: f64,
    pub usage: String,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SplineKind {
    InfinitePlate,
    Beam,
    ThinPlate,
}

/// The aerodynamic reference: coordinate system, velocity, chord, density, symmetry (AERO), or
/// the static reference (AEROS) with its chord, span and area.
#[derive(Clone, Debug, PartialEq)]
pub struct Aero {
    pub acsid: u32,
    pub velocity: Option<f64>,
    pub refc: f64,
    pub rhoref: f64,
    pub symxz: i64,
    pub symxy: i64,
}

/// AEROS: the static aerodynamic reference.
#[derive(Clone, Debug, PartialEq)]
pub struct Aeros {
    pub acsid: u32,
    pub rcsid: u32,
    pub refc: f64,
    pub refb: f64,
    pub refs: f64,
    pub symxz: i64,
    pub symxy: i64,
}

/// The flutter analysis: method (PK, PKNL, K, KE), density ratio, Mach and velocity (or reduced
/// frequency) FLFACT ids, interpolation method, number of values, convergence.
#[derive(Clone, Debug, PartialEq)]
pub struct Flutter {
    pub sid: u32,
    pub method: String,
    pub density: u32,
    pub mach: u32,
    pub velocity: u32,
    pub imeth: String,
    pub nvalue: Option<i64>,
    pub eps: f64,
}

/// A stationary vertical gust: the load set it multiplies, gust-to-flight speed ratio `wg`,
/// the gust's x location at t = 0, the flight speed.
#[derive(Clone, Debug, PartialEq)]
pub struct Gust {
    pub sid: u32,
    pub dload: u32,
    pub wg: f64,
    pub x0: f64,
    pub v: f64,
}

/// A frequency-dependent load (RLOAD1) or time-dependent load (TLOAD1): excitation set,
/// delay, tables.
#[derive(Clone, Debug, PartialEq)]
pub enum DynamicLoad {
    Rload1 {
        sid: u32,
        excite: u32,
        delay: Option<u32>,
        dphase: Option<u32>,
        tc: Option<u32>,
        td: Option<u32>,
    },
    Tload1 {
        sid: u32,
        excite: u32,
        delay: Option<u32>,
        kind: i64,
        tid: u32,
    },
}

/// A tabular function y(x) (TABLED1, TABRND1, TABDMP1): axes types, points, and TABDMP1's
/// damping type (G, CRIT, Q).
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    pub id: u32,
    pub card: &'static str,
    pub x_axis: String,
    pub y_axis: String,
    pub damping_type: String,
    pub points: Vec<(f64, f64)>,
}

/// A random excitation: load sets j and k, the complex factor x + iy, the PSD table.
#[derive(Clone, Debug, PartialEq)]
pub struct Randps {
    pub sid: u32,
    pub j: u32,
    pub k: u32,
    pub x: f64,
    pub y: f64,
    pub tid: Option<u32>,
}

/// A time step table: (number of steps, step, output every) per interval.
#[derive(Clone, Debug, PartialEq)]
pub struct Tstep {
    pub sid: u32,
    pub intervals: Vec<(u32, f64, u32)>,
}

/// A monitoring station (MONPNT1): the loads on a component's grids summed at a point.
#[derive(Clone, Debug, PartialEq)]
pub struct Monitor {
    pub name: String,
    pub label: String,
    /// The components reported: 1–3 forces, 4–6 moments, along CD's axes.
    pub axes: Vec<u8>,
    /// The AECOMP that lists the grids.
    pub comp: String,
    pub cp: u32,
    pub point: [f64; 3],
    pub cd: u32,
    pub source: super::Source,
}

/// AECOMP: a named list of SET1 grid sets (gustkit's monitoring stations sum structural
/// grids; lists of aerodynamic boxes are refused).
#[derive(Clone, Debug, PartialEq)]
pub struct Aecomp {
    pub name: String,
    pub sets: Vec<u32>,
    pub source: super::Source,
}

/// Every card a bulk data section held that gustkit uses, by kind and id.
#[derive(Clone, Debug, Default)]
pub struct BulkData {
    pub grids: BTreeMap<u32, Grid>,
    /// GRDSET's defaults for GRID's CP, CD and PS fields.
    pub grdset: Option<(u32, u32, Vec<u8>)>,
    pub coords: BTreeMap<u32, Cord2r>,
    pub masses: BTreeMap<u32, Conm>,
    pub springs: BTreeMap<u32, Scalar>,
    pub scalar_masses: BTreeMap<u32, Scalar>,
    pub bars: BTreeMap<u32, Bar>,
    pub bar_properties: BTreeMap<u32, BarProperty>,
    pub shells: BTreeMap<u32, Shell>,
    pub pshells: BTreeMap<u32, Pshell>,
    pub materials: BTreeMap<u32, Material>,
    pub genels: BTreeMap<u32, Genel>,
    pub rigids: BTreeMap<u32, Rigid>,
    pub mpcs: Vec<Mpc>,
    pub spcs: Vec<Spc>,
    /// SUPORT: grid components of the reference (free-body) set.
    pub suport: Vec<(u32, Vec<u8>)>,
    pub eigr: BTreeMap<u32, Eigr>,
    /// PARAM name → its first value as written.
    pub params: BTreeMap<String, String>,
    pub caero1: BTreeMap<u32, Caero1>,
    /// PAERO1: the bodies a CAERO1 interferes with (gustkit models none; kept to check ids).
    pub paero1: BTreeMap<u32, Vec<u32>>,
    pub aefact: BTreeMap<u32, Vec<f64>>,
    pub aelist: BTreeMap<u32, Vec<u32>>,
    pub splines: BTreeMap<u32, Spline>,
    pub set1: BTreeMap<u32, Vec<u32>>,
    pub aero: Option<Aero>,
    pub aeros: Option<Aeros>,
    /// MKAERO1/MKAERO2: (Mach, reduced frequency) pairs.
    pub mkaero: Vec<(f64, f64)>,
    pub flfact: BTreeMap<u32, Vec<f64>>,
    pub flutter: BTreeMap<u32, Flutter>,
    pub gusts: BTreeMap<u32, Gust>,
    pub dynamic_loads: BTreeMap<u32, DynamicLoad>,
    /// DAREA: set → (grid, component, scale) entries.
    pub darea: BTreeMap<u32, Vec<(u32, u8, f64)>>,
    pub tables: BTreeMap<u32, Table>,
    pub randps: Vec<Randps>,
    /// FREQ, FREQ1, FREQ2 by set, expanded to their frequencies (Hz).
    pub freq: BTreeMap<u32, Vec<f64>>,
    pub tstep: BTreeMap<u32, Tstep>,
    /// MONPNT1 by name, in the order of the names.
    pub monitors: BTreeMap<String, Monitor>,
    pub aecomps: BTreeMap<String, Aecomp>,
    /// One line naming the cards read but not used, if any.
    pub warnings: Vec<String>,
}

/// Cards gustkit reads but whose content cannot change what it computes, with the reason.
const READ_NOT_USED: [(&str, &str); 1] = [(
    "EIGC",
    "complex eigenvalue methods serve the K and KE flutter methods; gustkit runs the p-k",
)];

/// Inserts `v` under `id` or names the duplicate.
fn insert<T>(map: &mut BTreeMap<u32, T>, id: u32, v: T, card: &Card, kind: &str) -> R<()> {
    if map.insert(id, v).is_some() {
        return Err(NastranError::card(
            card,
            format!("duplicate {kind} id {id}: another card defines it before"),
        ));
    }
    Ok(())
}

impl BulkData {
    /// Sorts the cards of a deck into the model's data, checking each card's fields.
    pub fn from_cards(cards: &[Card]) -> R<Self> {
        let mut b = BulkData::default();
        let mut not_used: Vec<String> = Vec::new();
        for c in cards {
            b.read(c, &mut not_used)?;
        }
        if let Some((cp, cd, ps)) = b.grdset.clone() {
            for g in b.grids.values_mut() {
                if g.cp == u32::MAX {
                    g.cp = cp;
                }
                if g.cd == u32::MAX {
                    g.cd = cd;
                }
                if g.ps.is_empty() {
                    g.ps = ps.clone();
                }
            }
        }
        for g in b.grids.values_mut() {
            if g.cp == u32::MAX {
                g.cp = 0;
            }
            if g.cd == u32::MAX {
                g.cd = 0;
            }
        }
        if !not_used.is_empty() {
            b.warnings.push(format!(
                "bulk data: read but not used: {}",
                not_used.join("; ")
            ));
        }
        Ok(b)
    }

    /// One card into the model: each kind read by the method of its group; a card gustkit reads
    /// without use is named once in `not_used`, any other refused naming card and line.
    fn read(&mut self, c: &Card, not_used: &mut Vec<String>) -> R<()> {
        match c.name.as_str() {
            "GRID" | "GRDSET" | "CORD2R" | "CONM2" | "CONM1" | "CELAS2" | "CMASS2" | "CBAR"
            | "CBEAM" | "PBAR" | "PBEAM" | "CQUAD4" | "CTRIA3" | "PSHELL" | "MAT1" | "MAT8"
            | "GENEL" => self.read_structure(c),
            "RBE2" | "RBAR" | "MPC" | "SPC" | "SPC1" | "SUPORT" => self.read_constraint(c),
            "CAERO1" | "PAERO1" | "AEFACT" | "AELIST" | "MONPNT1" | "AECOMP" | "SET1"
            | "SPLINE1" | "SPLINE2" | "SPLINE4" | "AERO" | "AEROS" | "MKAERO1" | "MKAERO2"
            | "FLFACT" | "FLUTTER" => self.read_aero(c),
            "EIGR" | "EIGRL" | "PARAM" | "GUST" | "RLOAD1" | "TLOAD1" | "DAREA" | "TABLED1"
            | "TABRND1" | "TABDMP1" | "RANDPS" | "FREQ" | "FREQ1" | "FREQ2" | "TSTEP" => {
                self.read_dynamic(c)
            }
            other => {
                if let Some((_, why)) = READ_NOT_USED.iter().find(|(n, _)| *n == other) {
                    let line = format!("{other} ({why})");
                    if !not_used.contains(&line) {
                        not_used.push(line);
                    }
                    return Ok(());
                }
                Err(NastranError::card(
                    c,
                    "is not a card gustkit reads: remove it, or replace it by the cards listed in the README's Nastran input section (an element, property or load of another kind cannot be left out silently)",
                ))
            }
        }
    }

    /// Grids, frames, elements, properties and materials.
    fn read_structure(&mut self, c: &Card) -> R<()> {
        match c.name.as_str() {
            "GRID" => {
                let id = c.id_field(1, "ID")?;
                // blank CP/CD take GRDSET's defaults (marked until all cards are read)
                let cp = c.int_opt(2, "CP")?.map_or(u32::MAX, |v| v as u32);
                let cd = c.int_opt(6, "CD")?.map_or(u32::MAX, |v| v as u32);
                let g = Grid {
                    id,
                    cp,
                    x: [
                        c.real_or(3, "X1", 0.0)?,
                        c.real_or(4, "X2", 0.0)?,
                        c.real_or(5, "X3", 0.0)?,
                    ],
                    cd,
                    ps: c.components(7, "PS")?,
                };
                insert(&mut self.grids, id, g, c, "GRID")
            }
            "GRDSET" => {
                self.grdset = Some((
                    c.int_or(2, "CP", 0)? as u32,
                    c.int_or(6, "CD", 0)? as u32,
                    c.components(7, "PS")?,
                ));
                Ok(())
            }
            "CORD2R" => {
                let id = c.id_field(1, "CID")?;
                let p = |k: usize, n: &str| -> R<[f64; 3]> {
                    Ok([
                        c.real_or(k, &format!("{n}1"), 0.0)?,
                        c.real_or(k + 1, &format!("{n}2"), 0.0)?,
                        c.real_or(k + 2, &format!("{n}3"), 0.0)?,
                    ])
                };
                let cs = Cord2r {
                    id,
                    rid: c.int_or(2, "RID", 0)? as u32,
                    a: p(3, "A")?,
                    b: p(6, "B")?,
                    c: p(9, "C")?,
                };
                insert(&mut self.coords, id, cs, c, "coordinate system")
            }
            "CONM2" => {
                let id = c.id_field(1, "EID")?;
                let m = Conm::Conm2 {
                    id,
                    grid: c.id_field(2, "G")?,
                    cid: c.int_or(3, "CID", 0)?,
                    mass: c.real(4, "M")?,
                    offset: [
                        c.real_or(5, "X1", 0.0)?,
                        c.real_or(6, "X2", 0.0)?,
                        c.real_or(7, "X3", 0.0)?,
                    ],
                    inertia: {
                        let mut i = [0.0; 6];
                        for (k, v) in i.iter_mut().enumerate() {
                            *v = c.real_or(
                                9 + k,
                                ["I11", "I21", "I22", "I31", "I32", "I33"][k],
                                0.0,
                            )?;
                        }
                        i
                    },
                };
                insert(&mut self.masses, id, m, c, "mass element")
            }
            "CONM1" => {
                let id = c.id_field(1, "EID")?;
                let mut lower = [0.0; 21];
                for (i, v) in lower.iter_mut().enumerate() {
                    *v = c.real_or(4 + i, "Mij", 0.0)?;
                }
                let m = Conm::Conm1 {
                    id,
                    grid: c.id_field(2, "G")?,
                    cid: c.int_or(3, "CID", 0)? as u32,
                    lower,
                };
                insert(&mut self.masses, id, m, c, "mass element")
            }
            "CELAS2" | "CMASS2" => {
                let id = c.id_field(1, "EID")?;
                let component = |p: usize, what: &str| -> R<u8> {
                    let v = c.components(p, what)?;
                    match v.as_slice() {
                        [] => Ok(0),
                        [d] => Ok(*d),
                        _ => Err(c.field_error(p, what, "one component digit (1–6)")),
                    }
                };
                let s = Scalar {
                    id,
                    value: c.real(2, if c.name == "CELAS2" { "K" } else { "M" })?,
                    g1: c.int_or(3, "G1", 0)? as u32,
                    c1: component(4, "C1")?,
                    g2: c.int_or(5, "G2", 0)? as u32,
                    c2: component(6, "C2")?,
                    ge: if c.name == "CELAS2" {
                        c.real_or(7, "GE", 0.0)?
                    } else {
                        0.0
                    },
                };
                if s.g1 == 0 && s.g2 == 0 {
                    return Err(NastranError::card(c, "connects no grid (G1 and G2 blank)"));
                }
                if c.name == "CELAS2" {
                    insert(&mut self.springs, id, s, c, "spring")
                } else {
                    insert(&mut self.scalar_masses, id, s, c, "scalar mass")
                }
            }
            "CBAR" | "CBEAM" => {
                let id = c.id_field(1, "EID")?;
                let orientation = match c.value(5) {
                    Value::Int(_) if c.value(6) == Value::Blank && c.value(7) == Value::Blank => {
                        Orientation::Grid(c.id_field(5, "G0")?)
                    }
                    _ => Orientation::Vector([
                        c.real_or(5, "X1", 0.0)?,
                        c.real_or(6, "X2", 0.0)?,
                        c.real_or(7, "X3", 0.0)?,
                    ]),
                };
                // MSC's OFFT (GGG only), or NASTRAN-95's flag F (1: X1–X3 a vector, 2: X1 a grid)
                match c.value(8) {
                    Value::Blank | Value::Text("GGG") => {}
                    Value::Int(1) if !matches!(orientation, Orientation::Grid(_)) => {}
                    Value::Int(2) if matches!(orientation, Orientation::Grid(_)) => {}
                    _ => {
                        return Err(c.field_error(8, "OFFT", format!("only GGG (offsets and orientation in the grids' displacement systems) is read, or NASTRAN-95's flag F = 1 (vector) or 2 (grid) matching X1–X3 (got '{}')", c.raw(8))))
                    }
                }
                let w = |k: usize| -> R<[f64; 3]> {
                    Ok([
                        c.real_or(k, "W1", 0.0)?,
                        c.real_or(k + 1, "W2", 0.0)?,
                        c.real_or(k + 2, "W3", 0.0)?,
                    ])
                };
                let bar = Bar {
                    id,
                    pid: c.int_opt(2, "PID")?.map_or(id, |p| p as u32),
                    ga: c.id_field(3, "GA")?,
                    gb: c.id_field(4, "GB")?,
                    orientation,
                    pa: c.components(9, "PA")?,
                    pb: c.components(10, "PB")?,
                    wa: w(11)?,
                    wb: w(14)?,
                    beam: c.name == "CBEAM",
                };
                if bar.ga == bar.gb {
                    return Err(NastranError::card(
                        c,
                        format!("joins grid {} to itself", bar.ga),
                    ));
                }
                insert(&mut self.bars, id, bar, c, "bar or beam element")
            }
            "PBAR" => {
                let id = c.id_field(1, "PID")?;
                let p = BarProperty {
                    id,
                    mid: c.id_field(2, "MID")?,
                    area: c.real_or(3, "A", 0.0)?,
                    i1: c.real_or(4, "I1", 0.0)?,
                    i2: c.real_or(5, "I2", 0.0)?,
                    j: c.real_or(6, "J", 0.0)?,
                    nsm: c.real_or(7, "NSM", 0.0)?,
                    k1: c.real_opt(17, "K1")?,
                    k2: c.real_opt(18, "K2")?,
                    i12: c.real_or(19, "I12", 0.0)?,
                };
                insert(&mut self.bar_properties, id, p, c, "bar or beam property")
            }
            "PBEAM" => {
                let id = c.id_field(1, "PID")?;
                // a constant section: the first station only; a tapered beam names a station
                // (SO = YES/YESA/NO) in field 2 of a continuation
                if c.fields
                    .iter()
                    .skip(8)
                    .any(|f| matches!(f.as_str(), "YES" | "YESA" | "NO"))
                {
                    return Err(NastranError::card(c, "a tapered PBEAM (intermediate or end-B stations) is not read: give a constant section (the end-A values only) or split the beam"));
                }
                let p = BarProperty {
                    id,
                    mid: c.id_field(2, "MID")?,
                    area: c.real_or(3, "A(A)", 0.0)?,
                    i1: c.real_or(4, "I1(A)", 0.0)?,
                    i2: c.real_or(5, "I2(A)", 0.0)?,
                    i12: c.real_or(6, "I12(A)", 0.0)?,
                    j: c.real_or(7, "J(A)", 0.0)?,
                    nsm: c.real_or(8, "NSM(A)", 0.0)?,
                    k1: None,
                    k2: None,
                };
                insert(&mut self.bar_properties, id, p, c, "bar or beam property")
            }
            "CQUAD4" | "CTRIA3" => {
                let id = c.id_field(1, "EID")?;
                let n = if c.name == "CQUAD4" { 4 } else { 3 };
                let grids = (0..n)
                    .map(|i| c.id_field(3 + i, &format!("G{}", i + 1)))
                    .collect::<R<Vec<u32>>>()?;
                let (theta, mcid) = match c.value(3 + n) {
                    Value::Int(m) => (0.0, Some(m as u32)),
                    _ => (c.real_or(3 + n, "THETA", 0.0)?, None),
                };
                // continuation: two blanks, TFLAG, the corner thicknesses
                let corner_t = (0..n)
                    .map(|i| c.real_opt(12 + i, &format!("T{}", i + 1)))
                    .collect::<R<Vec<_>>>()?;
                if c.int_or(11, "TFLAG", 0)? != 0 {
                    return Err(c.field_error(
                        11,
                        "TFLAG",
                        "only TFLAG = 0 (corner thicknesses as lengths) is read",
                    ));
                }
                let mut unique = grids.clone();
                unique.sort_unstable();
                unique.dedup();
                if unique.len() != n {
                    return Err(NastranError::card(c, format!("repeats a grid ({grids:?})")));
                }
                let s = Shell {
                    id,
                    pid: c.int_opt(2, "PID")?.map_or(id, |p| p as u32),
                    grids,
                    theta,
                    mcid,
                    zoffs: c.real_or(4 + n, "ZOFFS", 0.0)?,
                    corner_t,
                };
                insert(&mut self.shells, id, s, c, "shell element")
            }
            "PSHELL" => {
                let id = c.id_field(1, "PID")?;
                let p = Pshell {
                    id,
                    mid1: c.id_opt(2, "MID1")?,
                    t: c.real_or(3, "T", 0.0)?,
                    mid2: match c.int_opt(4, "MID2")? {
                        Some(-1) => {
                            return Err(c.field_error(
                                4,
                                "MID2",
                                "MID2 = −1 (plane strain) is not read",
                            ))
                        }
                        _ => c.id_opt(4, "MID2")?,
                    },
                    bending_ratio: c.real_or(5, "12I/T**3", 1.0)?,
                    mid3: c.id_opt(6, "MID3")?,
                    ts_t: c.real_or(7, "TS/T", 0.833333)?,
                    nsm: c.real_or(8, "NSM", 0.0)?,
                };
                if let Some(m4) = c.id_opt(11, "MID4")? {
                    return Err(c.field_error(
                        11,
                        "MID4",
                        format!("membrane–bending coupling (MID4 = {m4}) is not read"),
                    ));
                }
                insert(&mut self.pshells, id, p, c, "shell property")
            }
            "MAT1" => {
                let id = c.id_field(1, "MID")?;
                let e = c.real_opt(2, "E")?;
                let g = c.real_opt(3, "G")?;
                let nu = c.real_opt(4, "NU")?;
                // Nastran's completion of E, G, ν from any two
                let (e, g, nu) = match (e, g, nu) {
                    (Some(e), Some(g), Some(nu)) => (e, g, nu),
                    (Some(e), Some(g), None) => (e, g, e / (2.0 * g) - 1.0),
                    (Some(e), None, Some(nu)) => (e, e / (2.0 * (1.0 + nu)), nu),
                    (None, Some(g), Some(nu)) => (2.0 * (1.0 + nu) * g, g, nu),
                    (Some(e), None, None) => (e, e / 2.0, 0.0),
                    (None, Some(g), None) => (0.0, g, 0.0),
                    _ => return Err(NastranError::card(c, "needs at least two of E, G and NU")),
                };
                let m = Material::Mat1 {
                    id,
                    e,
                    g,
                    nu,
                    rho: c.real_or(5, "RHO", 0.0)?,
                    ge: c.real_or(8, "GE", 0.0)?,
                };
                insert(&mut self.materials, id, m, c, "material")
            }
            "MAT8" => {
                let id = c.id_field(1, "MID")?;
                let m = Material::Mat8 {
                    id,
                    e1: c.real(2, "E1")?,
                    e2: c.real(3, "E2")?,
                    nu12: c.real(4, "NU12")?,
                    g12: c.real_or(5, "G12", 0.0)?,
                    g1z: c.real_or(6, "G1Z", 1e8)?,
                    g2z: c.real_or(7, "G2Z", 1e8)?,
                    rho: c.real_or(8, "RHO", 0.0)?,
                    ge: c.real_or(17, "GE", 0.0)?,
                };
                insert(&mut self.materials, id, m, c, "material")
            }
            "GENEL" => {
                let g = read_genel(c)?;
                insert(&mut self.genels, g.id, g, c, "general element")
            }
            other => unreachable!("read_structure was handed {other}"),
        }
    }

    /// Rigid elements, multipoint and single-point constraints, the free-body set.
    fn read_constraint(&mut self, c: &Card) -> R<()> {
        match c.name.as_str() {
            "RBE2" => {
                let id = c.id_field(1, "EID")?;
                let mut gm = Vec::new();
                for p in 4..=c.len() {
                    match c.value(p) {
                        Value::Int(g) if g > 0 => gm.push(g as u32),
                        Value::Blank => {}
                        // a real after the grids is the thermal expansion coefficient ALPHA
                        Value::Real(_) if p == c.len() => {}
                        Value::Text("THRU") => {
                            return Err(c.field_error(
                                p,
                                "GMi",
                                "THRU is not read on RBE2: list the grids",
                            ))
                        }
                        _ => {
                            return Err(c.field_error(
                                p,
                                "GMi",
                                format!("expected a grid id (got '{}')", c.raw(p)),
                            ))
                        }
                    }
                }
                if gm.is_empty() {
                    return Err(NastranError::card(c, "has no dependent grid"));
                }
                let r = Rigid::Rbe2 {
                    id,
                    gn: c.id_field(2, "GN")?,
                    cm: c.components(3, "CM")?,
                    gm,
                };
                insert(&mut self.rigids, id, r, c, "rigid element")
            }
            "RBAR" => {
                let id = c.id_field(1, "EID")?;
                let r = Rigid::Rbar {
                    id,
                    ga: c.id_field(2, "GA")?,
                    gb: c.id_field(3, "GB")?,
                    cna: c.components(4, "CNA")?,
                    cnb: c.components(5, "CNB")?,
                    cma: c.components(6, "CMA")?,
                    cmb: c.components(7, "CMB")?,
                };
                insert(&mut self.rigids, id, r, c, "rigid element")
            }
            "MPC" => {
                let sid = c.id_field(1, "SID")?;
                let mut terms = Vec::new();
                // G C A triples at fields 2–4 and 5–7 of every line (field 1 of a
                // continuation line is blank)
                let lines = c.len().div_ceil(8).max(1);
                for line in 0..lines {
                    for start in [2usize, 5] {
                        let p = 8 * line + start;
                        if c.value(p) == Value::Blank {
                            continue;
                        }
                        let comp = c.components(p + 1, "C")?;
                        let [comp] = comp.as_slice() else {
                            return Err(c.field_error(
                                p + 1,
                                "C",
                                "one component digit (0 for a scalar point is not read)",
                            ));
                        };
                        terms.push((c.id_field(p, "G")?, *comp, c.real(p + 2, "A")?));
                    }
                }
                if terms.is_empty() {
                    return Err(NastranError::card(c, "has no term"));
                }
                if terms[0].2 == 0.0 {
                    return Err(c.field_error(
                        4,
                        "A1",
                        "the dependent term's coefficient must not be zero",
                    ));
                }
                self.mpcs.push(Mpc {
                    sid,
                    terms,
                    source: c.source.clone(),
                });
                Ok(())
            }
            "SPC" => {
                let sid = c.id_field(1, "SID")?;
                for start in [2usize, 5] {
                    if c.value(start) == Value::Blank {
                        continue;
                    }
                    self.spcs.push(Spc {
                        sid,
                        grid: c.id_field(start, "G")?,
                        components: c.components(start + 1, "C")?,
                        value: c.real_or(start + 2, "D", 0.0)?,
                        source: c.source.clone(),
                    });
                }
                Ok(())
            }
            "SPC1" => {
                let sid = c.id_field(1, "SID")?;
                let components = c.components(2, "C")?;
                for g in id_list(c, 3, "G")? {
                    self.spcs.push(Spc {
                        sid,
                        grid: g,
                        components: components.clone(),
                        value: 0.0,
                        source: c.source.clone(),
                    });
                }
                Ok(())
            }
            "SUPORT" => {
                for start in (1..=c.len()).step_by(2) {
                    if c.value(start) == Value::Blank {
                        continue;
                    }
                    self.suport
                        .push((c.id_field(start, "ID")?, c.components(start + 1, "C")?));
                }
                Ok(())
            }
            other => unreachable!("read_constraint was handed {other}"),
        }
    }

    /// Lifting surfaces, splines, sets, monitor points and the aeroelastic solution cards.
    fn read_aero(&mut self, c: &Card) -> R<()> {
        match c.name.as_str() {
            "CAERO1" => {
                let id = c.id_field(1, "EID")?;
                let point = |k: usize, n: &str| -> R<[f64; 3]> {
                    Ok([
                        c.real_or(k, &format!("X{n}"), 0.0)?,
                        c.real_or(k + 1, &format!("Y{n}"), 0.0)?,
                        c.real_or(k + 2, &format!("Z{n}"), 0.0)?,
                    ])
                };
                let a = Caero1 {
                    id,
                    pid: c.id_field(2, "PID")?,
                    cp: c.int_or(3, "CP", 0)? as u32,
                    nspan: c.id_opt(4, "NSPAN")?,
                    nchord: c.id_opt(5, "NCHORD")?,
                    lspan: c.id_opt(6, "LSPAN")?,
                    lchord: c.id_opt(7, "LCHORD")?,
                    igid: c.int(8, "IGID")?,
                    p1: point(9, "1")?,
                    x12: c.real(12, "X12")?,
                    p4: point(13, "4")?,
                    x43: c.real_or(16, "X43", 0.0)?,
                };
                if a.nspan.is_none() && a.lspan.is_none() {
                    return Err(c.field_error(4, "NSPAN", "give NSPAN or an AEFACT in LSPAN"));
                }
                if a.nchord.is_none() && a.lchord.is_none() {
                    return Err(c.field_error(5, "NCHORD", "give NCHORD or an AEFACT in LCHORD"));
                }
                if !(a.x12 > 0.0) {
                    return Err(c.field_error(
                        12,
                        "X12",
                        format!("the root chord must be positive (got {})", a.x12),
                    ));
                }
                insert(&mut self.caero1, id, a, c, "CAERO")
            }
            "PAERO1" => {
                let id = c.id_field(1, "PID")?;
                let bodies = (2..=c.len())
                    .filter(|&p| c.value(p) != Value::Blank)
                    .map(|p| c.id_field(p, "Bi"))
                    .collect::<R<Vec<_>>>()?;
                insert(&mut self.paero1, id, bodies, c, "PAERO1")
            }
            "AEFACT" => {
                let id = c.id_field(1, "SID")?;
                let d = (2..=c.len())
                    .map(|p| c.real(p, "Di"))
                    .collect::<R<Vec<_>>>()?;
                insert(&mut self.aefact, id, d, c, "AEFACT")
            }
            "AELIST" => {
                let id = c.id_field(1, "SID")?;
                let l = id_list(c, 2, "Ei")?;
                insert(&mut self.aelist, id, l, c, "AELIST")
            }
            "MONPNT1" => {
                let name = c.text(1).to_string();
                if name.is_empty() {
                    return Err(c.field_error(1, "NAME", "a monitor point needs a name"));
                }
                let label = (2..=8)
                    .map(|i| c.text(i))
                    .filter(|t| !t.is_empty())
                    .collect::<Vec<_>>()
                    .join(" ");
                let comp = c.text(10).to_string();
                if comp.is_empty() {
                    return Err(c.field_error(10, "COMP", "names no AECOMP"));
                }
                let cp = c.int_or(11, "CP", 0)? as u32;
                let m = Monitor {
                    name: name.clone(),
                    label,
                    axes: c.components(9, "AXES")?,
                    comp,
                    cp,
                    point: [
                        c.real_or(12, "X", 0.0)?,
                        c.real_or(13, "Y", 0.0)?,
                        c.real_or(14, "Z", 0.0)?,
                    ],
                    cd: c.int_or(15, "CD", cp as i64)? as u32,
                    source: c.source.clone(),
                };
                if self.monitors.insert(name.clone(), m).is_some() {
                    return Err(NastranError::card(
                        c,
                        format!("duplicate monitor point name {name}"),
                    ));
                }
                Ok(())
            }
            "AECOMP" => {
                let name = c.text(1).to_string();
                if name.is_empty() {
                    return Err(c.field_error(1, "NAME", "a component needs a name"));
                }
                if c.text(2) != "SET1" {
                    return Err(c.field_error(
                        2,
                        "LISTTYPE",
                        "only SET1 lists (structural grids) are read: gustkit's monitor points sum the aerodynamic and inertial loads on grids",
                    ));
                }
                let sets = id_list(c, 3, "LISTID")?;
                if sets.is_empty() {
                    return Err(NastranError::card(c, "lists no SET1"));
                }
                let a = Aecomp {
                    name: name.clone(),
                    sets,
                    source: c.source.clone(),
                };
                if self.aecomps.insert(name.clone(), a).is_some() {
                    return Err(NastranError::card(
                        c,
                        format!("duplicate AECOMP name {name}"),
                    ));
                }
                Ok(())
            }
            "SET1" => {
                let id = c.id_field(1, "SID")?;
                let start = if c.text(2) == "SKIN" { 3 } else { 2 };
                let l = id_list(c, start, "Gi")?;
                if l.is_empty() {
                    return Err(NastranError::card(c, "is empty: a spline needs grids"));
                }
                insert(&mut self.set1, id, l, c, "SET1")
            }
            "SPLINE1" | "SPLINE2" | "SPLINE4" => {
                let id = c.id_field(1, "EID")?;
                let kind = match c.name.as_str() {
                    "SPLINE1" => SplineKind::InfinitePlate,
                    "SPLINE2" => SplineKind::Beam,
                    _ => SplineKind::ThinPlate,
                };
                let (boxes, aelist) = if kind == SplineKind::ThinPlate {
                    (None, Some(c.id_field(3, "AELIST")?))
                } else {
                    (Some((c.id_field(3, "BOX1")?, c.id_field(4, "BOX2")?)), None)
                };
                let usage_field = if kind == SplineKind::Beam { 12 } else { 8 };
                let s = Spline {
                    id,
                    kind,
                    caero: c.id_field(2, "CAERO")?,
                    boxes,
                    aelist,
                    setg: c.id_field(5, "SETG")?,
                    dz: c.real_or(6, "DZ", 0.0)?,
                    dtor: if kind == SplineKind::Beam {
                        c.real_or(7, "DTOR", 1.0)?
                    } else {
                        0.0
                    },
                    cid: if kind == SplineKind::Beam {
                        c.int_or(8, "CID", 0)? as u32
                    } else {
                        0
                    },
                    dthx: if kind == SplineKind::Beam {
                        c.real_or(9, "DTHX", 0.0)?
                    } else {
                        0.0
                    },
                    dthy: if kind == SplineKind::Beam {
                        c.real_or(10, "DTHY", 0.0)?
                    } else {
                        0.0
                    },
                    usage: match c.text(usage_field) {
                        "" => "BOTH".into(),
                        u @ ("FORCE" | "DISP" | "BOTH") => u.into(),
                        u => {
                            return Err(c.field_error(
                                usage_field,
                                "USAGE",
                                format!("FORCE, DISP or BOTH (got '{u}')"),
                            ))
                        }
                    },
                };
                if kind == SplineKind::InfinitePlate || kind == SplineKind::ThinPlate {
                    let meth = c.text(7);
                    if !(meth.is_empty() || meth == "IPS" || meth == "TPS") {
                        return Err(c.field_error(
                            7,
                            "METH",
                            format!(
                                "IPS or TPS is read (got '{meth}'; the finite-plate FPS is not)"
                            ),
                        ));
                    }
                }
                if let Some((b1, b2)) = s.boxes {
                    if b2 < b1 {
                        return Err(c.field_error(
                            4,
                            "BOX2",
                            format!("the last box {b2} comes before the first {b1}"),
                        ));
                    }
                }
                insert(&mut self.splines, id, s, c, "spline")
            }
            "AERO" => {
                if self.aero.is_some() {
                    return Err(NastranError::card(
                        c,
                        "a second AERO card: the model has one",
                    ));
                }
                self.aero = Some(Aero {
                    acsid: c.int_or(1, "ACSID", 0)? as u32,
                    velocity: c.real_opt(2, "VELOCITY")?,
                    refc: c.real(3, "REFC")?,
                    rhoref: c.real(4, "RHOREF")?,
                    symxz: c.int_or(5, "SYMXZ", 0)?,
                    symxy: c.int_or(6, "SYMXY", 0)?,
                });
                Ok(())
            }
            "AEROS" => {
                if self.aeros.is_some() {
                    return Err(NastranError::card(
                        c,
                        "a second AEROS card: the model has one",
                    ));
                }
                self.aeros = Some(Aeros {
                    acsid: c.int_or(1, "ACSID", 0)? as u32,
                    rcsid: c.int_or(2, "RCSID", 0)? as u32,
                    refc: c.real(3, "REFC")?,
                    refb: c.real(4, "REFB")?,
                    refs: c.real(5, "REFS")?,
                    symxz: c.int_or(6, "SYMXZ", 0)?,
                    symxy: c.int_or(7, "SYMXY", 0)?,
                });
                Ok(())
            }
            "MKAERO1" => {
                let machs: Vec<f64> = (1..=8)
                    .filter_map(|p| c.real_opt(p, "Mi").transpose())
                    .collect::<R<_>>()?;
                let ks: Vec<f64> = (9..=16)
                    .filter_map(|p| c.real_opt(p, "Ki").transpose())
                    .collect::<R<_>>()?;
                if machs.is_empty() || ks.is_empty() {
                    return Err(NastranError::card(c, "needs at least one Mach number (first line) and one reduced frequency (continuation)"));
                }
                for &m in &machs {
                    for &k in &ks {
                        self.mkaero.push((m, k));
                    }
                }
                Ok(())
            }
            "MKAERO2" => {
                for p in (1..=c.len()).step_by(2) {
                    if c.value(p) == Value::Blank {
                        continue;
                    }
                    self.mkaero.push((c.real(p, "Mi")?, c.real(p + 1, "Ki")?));
                }
                Ok(())
            }
            "FLFACT" => {
                let id = c.id_field(1, "SID")?;
                let values = if c.text(3) == "THRU" {
                    let (f1, fnf) = (c.real(2, "F1")?, c.real(4, "FNF")?);
                    let nf = c.int(5, "NF")?;
                    if nf < 2 {
                        return Err(c.field_error(5, "NF", "THRU needs at least 2 values"));
                    }
                    let fmid = c.real_opt(6, "FMID")?;
                    (0..nf)
                        .map(|i| {
                            let t = i as f64 / (nf - 1) as f64;
                            match fmid {
                                // Nastran's spacing through the middle value FMID
                                Some(fm) => {
                                    let x = (f1 * (fnf - fm) * (nf - 1 - i) as f64
                                        + fnf * (fm - f1) * i as f64)
                                        / ((fnf - fm) * (nf - 1 - i) as f64 + (fm - f1) * i as f64);
                                    if x.is_finite() {
                                        x
                                    } else {
                                        f1 + t * (fnf - f1)
                                    }
                                }
                                None => f1 + t * (fnf - f1),
                            }
                        })
                        .collect()
                } else {
                    (2..=c.len())
                        .map(|p| c.real(p, "Fi"))
                        .collect::<R<Vec<_>>>()?
                };
                insert(&mut self.flfact, id, values, c, "FLFACT")
            }
            "FLUTTER" => {
                let id = c.id_field(1, "SID")?;
                let f = Flutter {
                    sid: id,
                    method: c.text(2).to_string(),
                    density: c.id_field(3, "DENS")?,
                    mach: c.id_field(4, "MACH")?,
                    velocity: c.id_field(5, "RFREQ/VEL")?,
                    imeth: match c.text(6) {
                        "" => "L".into(),
                        t => t.into(),
                    },
                    nvalue: c.int_opt(7, "NVALUE")?,
                    eps: c.real_or(8, "EPS", 1e-3)?,
                };
                if !matches!(
                    f.method.as_str(),
                    "PK" | "PKNL" | "K" | "KE" | "PKS" | "PKNLS"
                ) {
                    return Err(c.field_error(
                        2,
                        "METHOD",
                        format!("PK, PKNL, K or KE (got '{}')", f.method),
                    ));
                }
                insert(&mut self.flutter, id, f, c, "FLUTTER")
            }
            other => unreachable!("read_aero was handed {other}"),
        }
    }

    /// Eigenvalue methods, parameters, dynamic loads, tables, frequencies and time steps.
    fn read_dynamic(&mut self, c: &Card) -> R<()> {
        match c.name.as_str() {
            "EIGR" | "EIGRL" => {
                let sid = c.id_field(1, "SID")?;
                let e = if c.name == "EIGR" {
                    Eigr {
                        sid,
                        method: c.text(2).to_string(),
                        f1: c.real_opt(3, "F1")?,
                        f2: c.real_opt(4, "F2")?,
                        nd: c.int_opt(6, "ND")?.map(|n| n as u32),
                        norm: c.text(9).to_string(),
                    }
                } else {
                    Eigr {
                        sid,
                        method: "LAN".into(),
                        f1: c.real_opt(2, "V1")?,
                        f2: c.real_opt(3, "V2")?,
                        nd: c.int_opt(4, "ND")?.map(|n| n as u32),
                        norm: c.text(8).to_string(),
                    }
                };
                if e.nd.is_none() && e.f2.is_none() {
                    return Err(NastranError::card(
                        c,
                        "asks for no roots: give ND or an upper frequency",
                    ));
                }
                insert(&mut self.eigr, sid, e, c, "eigenvalue method")
            }
            "PARAM" => {
                let name = c.text(1).to_string();
                if name.is_empty() {
                    return Err(c.field_error(1, "N", "names no parameter"));
                }
                self.params.insert(name, c.text(2).to_string());
                Ok(())
            }
            "GUST" => {
                let id = c.id_field(1, "SID")?;
                let g = Gust {
                    sid: id,
                    dload: c.id_field(2, "DLOAD")?,
                    wg: c.real(3, "WG")?,
                    x0: c.real_or(4, "X0", 0.0)?,
                    v: c.real(5, "V")?,
                };
                insert(&mut self.gusts, id, g, c, "GUST")
            }
            "RLOAD1" => {
                let sid = c.id_field(1, "SID")?;
                let l = DynamicLoad::Rload1 {
                    sid,
                    excite: c.id_field(2, "EXCITEID")?,
                    delay: c.id_opt(3, "DELAY")?,
                    dphase: c.id_opt(4, "DPHASE")?,
                    tc: c.id_opt(5, "TC")?,
                    td: c.id_opt(6, "TD")?,
                };
                insert(&mut self.dynamic_loads, sid, l, c, "dynamic load")
            }
            "TLOAD1" => {
                let sid = c.id_field(1, "SID")?;
                let l = DynamicLoad::Tload1 {
                    sid,
                    excite: c.id_field(2, "EXCITEID")?,
                    delay: c.id_opt(3, "DELAY")?,
                    kind: c.int_or(4, "TYPE", 0)?,
                    tid: c.id_field(5, "TID")?,
                };
                insert(&mut self.dynamic_loads, sid, l, c, "dynamic load")
            }
            "DAREA" => {
                let sid = c.id_field(1, "SID")?;
                for start in [2usize, 5] {
                    if c.value(start) == Value::Blank {
                        continue;
                    }
                    let comp = c.components(start + 1, "C")?;
                    let comp = comp.first().copied().unwrap_or(0);
                    self.darea.entry(sid).or_default().push((
                        c.id_field(start, "P")?,
                        comp,
                        c.real(start + 2, "A")?,
                    ));
                }
                Ok(())
            }
            "TABLED1" | "TABRND1" | "TABDMP1" => {
                let id = c.id_field(1, "TID")?;
                let name: &'static str = match c.name.as_str() {
                    "TABLED1" => "TABLED1",
                    "TABRND1" => "TABRND1",
                    _ => "TABDMP1",
                };
                let axis = |p: usize| match c.text(p) {
                    "" => Ok("LINEAR".to_string()),
                    a @ ("LINEAR" | "LOG") => Ok(a.to_string()),
                    a => Err(c.field_error(p, "axis", format!("LINEAR or LOG (got '{a}')"))),
                };
                let (x_axis, y_axis, damping_type) = if name == "TABDMP1" {
                    (
                        "LINEAR".into(),
                        "LINEAR".into(),
                        match c.text(2) {
                            "" => "G".to_string(),
                            t @ ("G" | "CRIT" | "Q") => t.to_string(),
                            t => {
                                return Err(c.field_error(
                                    2,
                                    "TYPE",
                                    format!("G, CRIT or Q (got '{t}')"),
                                ))
                            }
                        },
                    )
                } else {
                    (axis(2)?, axis(3)?, String::new())
                };
                let mut points = Vec::new();
                let mut p = 9;
                loop {
                    match c.text(p) {
                        "ENDT" => break,
                        "SKIP" => {
                            p += 2;
                            continue;
                        }
                        "" if p > c.len() => {
                            return Err(NastranError::card(c, "has no ENDT after its points"))
                        }
                        _ => {}
                    }
                    let x = c.real(p, "xi")?;
                    let y = c.real(p + 1, "yi")?;
                    if points.last().is_some_and(|&(x0, _): &(f64, f64)| x < x0) {
                        return Err(c.field_error(
                            p,
                            "xi",
                            format!(
                                "x values must not decrease ({x} after {})",
                                points.last().unwrap().0
                            ),
                        ));
                    }
                    points.push((x, y));
                    p += 2;
                }
                if points.is_empty() {
                    return Err(NastranError::card(c, "has no points"));
                }
                let t = Table {
                    id,
                    card: name,
                    x_axis,
                    y_axis,
                    damping_type,
                    points,
                };
                insert(&mut self.tables, id, t, c, "table")
            }
            "RANDPS" => {
                self.randps.push(Randps {
                    sid: c.id_field(1, "SID")?,
                    j: c.id_field(2, "J")?,
                    k: c.id_field(3, "K")?,
                    x: c.real_or(4, "X", 0.0)?,
                    y: c.real_or(5, "Y", 0.0)?,
                    tid: c.id_opt(6, "TID")?,
                });
                Ok(())
            }
            "FREQ" | "FREQ1" | "FREQ2" => {
                let sid = c.id_field(1, "SID")?;
                let f: Vec<f64> = match c.name.as_str() {
                    "FREQ" => (2..=c.len()).map(|p| c.real(p, "Fi")).collect::<R<_>>()?,
                    "FREQ1" => {
                        let (f1, df, n) = (
                            c.real_or(2, "F1", 0.0)?,
                            c.real(3, "DF")?,
                            c.int_or(4, "NDF", 1)?,
                        );
                        if !(df > 0.0) || n < 1 {
                            return Err(NastranError::card(c, "needs DF > 0 and NDF ≥ 1"));
                        }
                        (0..=n).map(|i| f1 + i as f64 * df).collect()
                    }
                    _ => {
                        let (f1, f2, n) =
                            (c.real(2, "F1")?, c.real(3, "F2")?, c.int_or(4, "NF", 1)?);
                        if !(f1 > 0.0 && f2 > f1) || n < 1 {
                            return Err(NastranError::card(c, "needs 0 < F1 < F2 and NF ≥ 1"));
                        }
                        (0..=n)
                            .map(|i| f1 * (f2 / f1).powf(i as f64 / n as f64))
                            .collect()
                    }
                };
                self.freq.entry(sid).or_default().extend(f);
                Ok(())
            }
            "TSTEP" => {
                let sid = c.id_field(1, "SID")?;
                let mut intervals = Vec::new();
                for line in 0..c.len().div_ceil(8).max(1) {
                    let p = 8 * line + 2;
                    if c.value(p) == Value::Blank {
                        continue;
                    }
                    intervals.push((
                        c.id_field(p, "Ni")?,
                        c.real(p + 1, "DTi")?,
                        c.int_or(p + 2, "NOi", 1)? as u32,
                    ));
                }
                insert(&mut self.tstep, sid, Tstep { sid, intervals }, c, "TSTEP")
            }

            other => unreachable!("read_dynamic was handed {other}"),
        }
    }
}

/// An id list from field `start` on: ids, `a THRU b`, blanks skipped.
fn id_list(c: &Card, start: usize, what: &str) -> R<Vec<u32>> {
    let mut out = Vec::new();
    let mut p = start;
    while p <= c.len() {
        match c.value(p) {
            Value::Blank => p += 1,
            Value::Text("THRU") => {
                let a = *out
                    .last()
                    .ok_or_else(|| c.field_error(p, what, "THRU without a first id"))?;
                let b = c.id_field(p + 1, what)?;
                if b < a {
                    return Err(c.field_error(p + 1, what, format!("{a} THRU {b} runs backwards")));
                }
                out.extend(a + 1..=b);
                p += 2;
            }
            _ => {
                out.push(c.id_field(p, what)?);
                p += 1;
            }
        }
    }
    Ok(out)
}

/// GENEL: UI pairs, `UD` and its pairs, `K` or `Z` and the lower triangle, `S` and its terms.
fn read_genel(c: &Card) -> R<Genel> {
    let id = c.id_field(1, "EID")?;
    let mut ui = Vec::new();
    let mut ud = Vec::new();
    let mut matrix = Vec::new();
    let mut s = Vec::new();
    let mut flexibility = None;
    #[derive(PartialEq)]
    enum Part {
        Ui,
        Ud,
        Matrix,
        S,
    }
    let mut part = Part::Ui;
    let mut p = 3;
    while p <= c.len() {
        match (c.text(p), &part) {
            ("", _) => {
                p += 1;
                continue;
            }
            ("UD", Part::Ui) => part = Part::Ud,
            ("K" | "Z", Part::Ui | Part::Ud) => {
                flexibility = Some(c.text(p) == "Z");
                part = Part::Matrix;
            }
            ("S", Part::Matrix) => part = Part::S,
            (_, Part::Ui | Part::Ud) => {
                let g = c.id_field(p, "UI/UD grid")?;
                let comp = c.components(p + 1, "component")?;
                let comp = comp.first().copied().unwrap_or(0);
                if part == Part::Ui {
                    ui.push((g, comp));
                } else {
                    ud.push((g, comp));
                }
                p += 2;
                continue;
            }
            (_, Part::Matrix) => matrix.push(c.real(p, "KIJ/ZIJ")?),
            (_, Part::S) => s.push(c.real(p, "SIJ")?),
        }
        p += 1;
    }
    let Some(flexibility) = flexibility else {
        return Err(NastranError::card(c, "has no K or Z matrix"));
    };
    let m = ui.len();
    if matrix.len() != m * (m + 1) / 2 {
        return Err(NastranError::card(
            c,
            format!(
                "its {} matrix has {} terms; {m} independent components need {} (the lower triangle)",
                if flexibility { "Z" } else { "K" },
                matrix.len(),
                m * (m + 1) / 2
            ),
        ));
    }
    if !ud.is_empty() && s.len() != m * ud.len() {
        return Err(NastranError::card(
            c,
            format!(
                "its S matrix has {} terms; {m} × {} are needed",
                s.len(),
                ud.len()
            ),
        ));
    }
    Ok(Genel {
        id,
        ui,
        ud,
        flexibility,
        matrix,
        s,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nastran::Deck;
    use std::path::Path;

    fn bulk(text: &str) -> R<BulkData> {
        let d = Deck::from_text(Path::new("m.bdf"), &format!("BEGIN BULK\n{text}ENDDATA\n"))?;
        BulkData::from_cards(&d.bulk)
    }

    /// Bad bulk data is refused naming the file, line, card, id and the reason.
    #[test]
    fn bad_cards_are_named() {
        for (text, needles) in [
            (
                "GRID,1,,0.,0.,0.\nGRID,1,,1.,0.,0.\n",
                &["m.bdf line 3", "GRID 1", "duplicate GRID id 1"][..],
            ),
            (
                "CHEXA,5,1,1,2,3,4,5,6\n",
                &["CHEXA 5", "not a card gustkit reads"],
            ),
            (
                "CQUAD4,7,1,1,2,3\n",
                &["CQUAD4 7", "field 7 (G4)", "missing"],
            ),
            ("CQUAD4,7,1,1,2,3,3\n", &["repeats a grid"]),
            (
                "CBAR,3,1,4,4,0.,0.,1.\n",
                &["CBAR 3", "joins grid 4 to itself"],
            ),
            ("SPC1,1,123,9,THRU,5\n", &["runs backwards"]),
            ("MPC,1,5,3,0.,6,3,1.\n", &["MPC 1", "must not be zero"]),
            (
                "TABLED1,4\n,1.,0.,0.5,1.,ENDT\n",
                &["TABLED1 4", "must not decrease"],
            ),
            ("TABLED1,4\n,1.,0.,2.,1.\n", &["has no ENDT"]),
            (
                "GENEL,9,,1,3,2,3,K,1.,2.\n",
                &["GENEL 9", "3 (the lower triangle)"],
            ),
            (
                "CAERO1,1,1,0,4,4,,,1\n,0.,0.,0.,-1.,0.,1.,0.,1.\n",
                &["X12", "must be positive"],
            ),
            (
                "SPLINE1,5,100,101,110,3,0.,FPS\n",
                &["SPLINE1 5", "finite-plate"],
            ),
            ("PSHELL,1,1,0.1,1,,,,\n,,,2\n", &["MID4"]),
            ("MAT1,1,,,0.3\n", &["at least two of E, G and NU"]),
            ("FLUTTER,1,XX,1,2,3\n", &["PK, PKNL, K or KE"]),
            ("AERO,0,1.,1.,1.\nAERO,0,2.,1.,1.\n", &["a second AERO"]),
        ] {
            let e = bulk(text).unwrap_err().to_string();
            for n in needles {
                assert!(e.contains(n), "{text:?}: '{e}' lacks '{n}'");
            }
        }
    }

    /// MAT1 completes E, G, ν from any two as Nastran does; FLFACT's THRU with and without FMID
    /// (the middle value lands where asked); GRDSET fills blank CP, CD, PS; FREQ2 is geometric.
    #[test]
    fn defaults_and_generated_lists() {
        let b = bulk(
            "MAT1,1,70.+9,,0.25,2700.\nMAT1,2,,26.+9,0.3\nFLFACT,1,100.,THRU,300.,5\n\
             FLFACT,2,1.,THRU,3.,3,1.5\nGRDSET,,,,,,3,456\nGRID,1,,0.,0.,0.\nGRID,2,,0.,0.,0.,,1\n\
             FREQ2,7,1.,100.,2\n",
        )
        .unwrap();
        match (&b.materials[&1], &b.materials[&2]) {
            (Material::Mat1 { g, .. }, Material::Mat1 { e, .. }) => {
                assert_eq!(*g, 70e9 / 2.5);
                assert!((e - 2.0 * 1.3 * 26e9).abs() < 1e-3);
            }
            m => panic!("{m:?}"),
        }
        assert_eq!(b.flfact[&1], vec![100.0, 150.0, 200.0, 250.0, 300.0]);
        assert_eq!(b.flfact[&2][1], 1.5);
        assert_eq!((b.grids[&1].cd, b.grids[&1].ps.clone()), (3, vec![4, 5, 6]));
        assert_eq!(b.grids[&2].ps, vec![1]);
        assert_eq!(b.freq[&7], vec![1.0, 10.0, 100.0]);
    }
}
