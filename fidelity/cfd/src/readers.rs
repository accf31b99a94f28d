//! Meshes from files: Gmsh MSH 4.1 and the SU2 native format (ASCII, 2-D or 3-D), and the general builder
//! from cells (tetrahedra, pyramids, prisms, hexahedra) and marked boundary faces. 2-D meshes
//! (triangles, quadrilaterals) are extruded one cell thick with symmetry planes, so they run on the
//! 3-D code path.

use crate::mesh::{face_area, face_center, Boundary, Face, Mesh, Side};
use std::collections::HashMap;

/// Why a mesh file cannot be read; the line number is 1-based.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ReadError {
    #[error("line {line}: {reason}")]
    Syntax { line: usize, reason: String },
    #[error("boundary marker '{marker}' is not in the study's marker map (known: {known:?})")]
    UnknownMarker { marker: String, known: Vec<String> },
    #[error("{0}")]
    Topology(String),
}

/// Outward faces of a cell by its node count (VTK orderings; orientation is fixed afterwards).
fn cell_faces(cell: &[usize]) -> Result<Vec<Vec<usize>>, ReadError> {
    let c = cell;
    Ok(match c.len() {
        4 => vec![
            vec![c[0], c[2], c[1]],
            vec![c[0], c[1], c[3]],
            vec![c[1], c[2], c[3]],
            vec![c[2], c[0], c[3]],
        ],
        5 => vec![
            vec![c[0], c[3], c[2], c[1]],
            vec![c[0], c[1], c[4]],
            vec![c[1], c[2], c[4]],
            vec![c[2], c[3], c[4]],
            vec![c[3], c[0], c[4]],
        ],
        6 => vec![
            vec![c[0], c[1], c[2]],
            vec![c[3], c[5], c[4]],
            vec![c[0], c[3], c[4], c[1]],
            vec![c[1], c[4], c[5], c[2]],
            vec![c[2], c[5], c[3], c[0]],
        ],
        8 => vec![
            vec![c[0], c[3], c[2], c[1]],
            vec![c[4], c[5], c[6], c[7]],
            vec![c[0], c[1], c[5], c[4]],
            vec![c[1], c[2], c[6], c[5]],
            vec![c[2], c[3], c[7], c[6]],
            vec![c[3], c[0], c[4], c[7]],
        ],
        n => {
            return Err(ReadError::Topology(format!(
                "a cell with {n} nodes (expected 4, 5, 6 or 8)"
            )))
        }
    })
}

/// Builds the face structure from cells and marked boundary faces: interior faces are matched by
/// their node sets, every face is oriented out of its left cell (by the cell centroid), and every
/// unmatched cell face must be a marked boundary face.
pub fn from_cells(
    nodes: Vec<[f64; 3]>,
    cells: Vec<Vec<usize>>,
    boundary: Vec<(Vec<usize>, Boundary)>,
) -> Result<Mesh, ReadError> {
    let key = |f: &[usize]| {
        let mut k = f.to_vec();
        k.sort_unstable();
        k
    };
    let centroid = |ids: &[usize]| -> [f64; 3] {
        std::array::from_fn(|i| ids.iter().map(|&n| nodes[n][i]).sum::<f64>() / ids.len() as f64)
    };
    for (ci, c) in cells.iter().enumerate() {
        if let Some(&n) = c.iter().find(|&&n| n >= nodes.len()) {
            return Err(ReadError::Topology(format!(
                "cell {ci} refers to node {n} of {}",
                nodes.len()
            )));
        }
    }
    let mut open: HashMap<Vec<usize>, usize> = HashMap::new();
    let mut faces: Vec<Face> = Vec::new();
    for (ci, c) in cells.iter().enumerate() {
        let cc = centroid(c);
        for mut f in cell_faces(c)? {
            // orient out of this cell
            let pts: Vec<[f64; 3]> = f.iter().map(|&n| nodes[n]).collect();
            let (s, fc) = (face_area(&pts), face_center(&pts));
            if (0..3).map(|i| s[i] * (fc[i] - cc[i])).sum::<f64>() < 0.0 {
                f.reverse();
            }
            match open.remove(&key(&f)) {
                Some(fi) => {
                    if faces[fi].right != Side::Boundary(Boundary::Wall) || faces[fi].left == ci {
                        return Err(ReadError::Topology(format!(
                            "a face of cell {ci} is shared by more than two cells"
                        )));
                    }
                    faces[fi].right = Side::Cell(ci);
                }
                None => {
                    open.insert(key(&f), faces.len());
                    // provisional: a boundary until a second cell claims it
                    faces.push(Face {
                        nodes: f,
                        left: ci,
                        right: Side::Boundary(Boundary::Wall),
                    });
                }
            }
        }
    }
    for (bnodes, kind) in boundary {
        match open.remove(&key(&bnodes)) {
            Some(fi) => faces[fi].right = Side::Boundary(kind),
            None => {
                return Err(ReadError::Topology(format!(
                    "boundary face {bnodes:?} ({kind:?}) is not a free face of any cell"
                )))
            }
        }
    }
    if let Some((k, _)) = open.into_iter().next() {
        return Err(ReadError::Topology(format!(
            "the cell face {k:?} is on the boundary but has no marker"
        )));
    }
    Ok(Mesh {
        nodes,
        faces,
        n_cells: cells.len(),
        cells,
    })
}

/// Extrudes a 2-D mesh (triangles, quadrilaterals in the x-y plane; boundary edges) one layer of
/// thickness `dz`: prisms and hexahedra, boundary quads, symmetry planes at z = 0 and z = dz.
pub fn extrude(
    nodes2: &[[f64; 2]],
    cells2: &[Vec<usize>],
    edges: &[(Vec<usize>, Boundary)],
    dz: f64,
) -> Result<Mesh, ReadError> {
    let np = nodes2.len();
    let mut nodes: Vec<[f64; 3]> = nodes2.iter().map(|p| [p[0], p[1], 0.0]).collect();
    nodes.extend(nodes2.iter().map(|p| [p[0], p[1], dz]));
    let mut cells = Vec::new();
    let mut boundary = Vec::new();
    for c in cells2 {
        let mut c3: Vec<usize> = c.clone();
        c3.extend(c.iter().map(|n| n + np));
        if c.len() != 3 && c.len() != 4 {
            return Err(ReadError::Topology(format!(
                "a 2-D cell with {} nodes (expected 3 or 4)",
                c.len()
            )));
        }
        boundary.push((c.clone(), Boundary::Symmetry));
        boundary.push((c.iter().map(|n| n + np).collect(), Boundary::Symmetry));
        cells.push(c3);
    }
    for (e, kind) in edges {
        if e.len() != 2 {
            return Err(ReadError::Topology("a boundary edge needs 2 nodes".into()));
        }
        boundary.push((vec![e[0], e[1], e[1] + np, e[0] + np], *kind));
    }
    let mut mesh = from_cells(nodes, cells, boundary)?;
    // hexahedra in VTK order for output: the bottom quad turning about +z
    for c in mesh.cells.iter_mut().filter(|c| c.len() == 8) {
        let pts: Vec<[f64; 3]> = c[..4].iter().map(|&n| mesh.nodes[n]).collect();
        if face_area(&pts)[2] < 0.0 {
            *c = vec![c[0], c[3], c[2], c[1], c[4], c[7], c[6], c[5]];
        }
    }
    Ok(mesh)
}

/// Parses an SU2 mesh (`NDIME`, `NELEM`, `NPOIN`, `NMARK` sections). Boundary markers are mapped
/// to boundary conditions by `markers` (marker name → condition); a marker not in the map is an
/// error. 2-D meshes are extruded to thickness `dz`.
pub fn read_su2(
    text: &str,
    markers: &HashMap<String, Boundary>,
    dz: f64,
) -> Result<Mesh, ReadError> {
    let lines: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.split('%').next().unwrap_or("").trim()))
        .filter(|(_, l)| !l.is_empty())
        .collect();
    let syntax = |line: usize, reason: String| ReadError::Syntax { line, reason };
    let mut pos = 0;
    // the count after `NAME=` on the next line that starts with it
    fn count(
        lines: &[(usize, &str)],
        pos: &mut usize,
        name: &str,
    ) -> Result<(usize, usize), ReadError> {
        while *pos < lines.len() {
            let (ln, l) = lines[*pos];
            *pos += 1;
            if let Some(rest) = l.strip_prefix(name) {
                let v = rest
                    .trim_start_matches([' ', '='])
                    .split_whitespace()
                    .next()
                    .unwrap_or("");
                return v.parse().map(|v| (ln, v)).map_err(|_| ReadError::Syntax {
                    line: ln,
                    reason: format!("{name} needs a count, got '{v}'"),
                });
            }
        }
        Err(ReadError::Syntax {
            line: lines.last().map_or(0, |l| l.0),
            reason: format!("missing {name}"),
        })
    }
    let ints = |ln: usize, l: &str| -> Result<Vec<usize>, ReadError> {
        l.split_whitespace()
            .map(|t| {
                t.parse::<usize>()
                    .map_err(|_| syntax(ln, format!("'{t}' is not an index")))
            })
            .collect()
    };
    let (_, ndime) = count(&lines, &mut pos, "NDIME")?;
    if ndime != 2 && ndime != 3 {
        return Err(syntax(
            lines[0].0,
            format!("NDIME must be 2 or 3, got {ndime}"),
        ));
    }
    let (_, nelem) = count(&lines, &mut pos, "NELEM")?;
    let start = pos;
    let mut cells = Vec::with_capacity(nelem);
    for i in 0..nelem {
        let (ln, l) = *lines
            .get(start + i)
            .ok_or_else(|| syntax(0, "the element list ends early".into()))?;
        let v = ints(ln, l)?;
        let n = match v.first() {
            Some(5) => 3,
            Some(9) => 4,
            Some(10) => 4,
            Some(14) => 5,
            Some(13) => 6,
            Some(12) => 8,
            Some(t) => return Err(syntax(ln, format!("unsupported element type {t}"))),
            None => return Err(syntax(ln, "empty element line".into())),
        };
        if v.len() < 1 + n {
            return Err(syntax(ln, format!("element needs {n} nodes")));
        }
        cells.push(v[1..=n].to_vec());
    }
    pos = start + nelem;
    let (_, npoin) = count(&lines, &mut pos, "NPOIN")?;
    let start = pos;
    let mut points = Vec::with_capacity(npoin);
    for i in 0..npoin {
        let (ln, l) = *lines
            .get(start + i)
            .ok_or_else(|| syntax(0, "the point list ends early".into()))?;
        let v: Vec<f64> = l
            .split_whitespace()
            .take(ndime)
            .map(|t| {
                t.parse::<f64>()
                    .map_err(|_| syntax(ln, format!("'{t}' is not a number")))
            })
            .collect::<Result<_, _>>()?;
        if v.len() < ndime {
            return Err(syntax(ln, format!("a point needs {ndime} coordinates")));
        }
        points.push(v);
    }
    pos = start + npoin;
    let (_, nmark) = count(&lines, &mut pos, "NMARK")?;
    let mut bfaces = Vec::new();
    let known: Vec<String> = markers.keys().cloned().collect();
    for _ in 0..nmark {
        let (ln, tag) = loop {
            let (ln, l) = *lines
                .get(pos)
                .ok_or_else(|| syntax(0, "missing MARKER_TAG".into()))?;
            pos += 1;
            if let Some(rest) = l.strip_prefix("MARKER_TAG") {
                break (ln, rest.trim_start_matches([' ', '=']).trim().to_string());
            }
        };
        let kind = *markers.get(&tag).ok_or_else(|| ReadError::UnknownMarker {
            marker: tag.clone(),
            known: known.clone(),
        })?;
        let (_, n) = count(&lines, &mut pos, "MARKER_ELEMS")?;
        for i in 0..n {
            let (ln2, l) = *lines
                .get(pos + i)
                .ok_or_else(|| syntax(ln, format!("marker {tag} ends early")))?;
            let v = ints(ln2, l)?;
            let m = match v.first() {
                Some(3) => 2,
                Some(5) => 3,
                Some(9) => 4,
                _ => return Err(syntax(ln2, "unsupported boundary element".into())),
            };
            if v.len() < 1 + m {
                return Err(syntax(ln2, format!("boundary element needs {m} nodes")));
            }
            bfaces.push((v[1..=m].to_vec(), kind));
        }
        pos += n;
    }
    if ndime == 2 {
        let nodes2: Vec<[f64; 2]> = points.iter().map(|p| [p[0], p[1]]).collect();
        extrude(&nodes2, &cells, &bfaces, dz)
    } else {
        let nodes: Vec<[f64; 3]> = points.iter().map(|p| [p[0], p[1], p[2]]).collect();
        from_cells(nodes, cells, bfaces)
    }
}

/// A Gmsh element: its (dimension, entity), its nodes (indices into the node list), its line.
type GmshElement = ((usize, usize), Vec<usize>, usize);

/// Parses a Gmsh mesh in the MSH 4.1 ASCII format: `$PhysicalNames`, `$Entities` (physical tags
/// of the entities), `$Nodes` and `$Elements`. The cells are the elements of the highest
/// dimension; the elements one dimension lower are boundary faces, named by the physical name of
/// their entity and mapped by `markers`. 2-D meshes are extruded to thickness `dz`.
pub fn read_gmsh(
    text: &str,
    markers: &HashMap<String, Boundary>,
    dz: f64,
) -> Result<Mesh, ReadError> {
    let lines: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty())
        .collect();
    let syntax = |line: usize, reason: String| ReadError::Syntax { line, reason };
    let section = |name: &str| -> Result<usize, ReadError> {
        lines
            .iter()
            .position(|(_, l)| *l == name)
            .map(|p| p + 1)
            .ok_or_else(|| syntax(0, format!("missing {name}")))
    };
    let nums = |ln: usize, l: &str| -> Result<Vec<f64>, ReadError> {
        l.split_whitespace()
            .map(|t| {
                t.parse::<f64>()
                    .map_err(|_| syntax(ln, format!("'{t}' is not a number")))
            })
            .collect()
    };
    let fmt = section("$MeshFormat")?;
    let (ln, l) = lines[fmt];
    if !l.starts_with("4.1") {
        return Err(syntax(ln, format!("MSH format 4.1 expected, got '{l}'")));
    }
    // physical names: (dim, tag) -> name
    let mut names: HashMap<(usize, usize), String> = HashMap::new();
    if let Ok(p) = section("$PhysicalNames") {
        let n = nums(lines[p].0, lines[p].1)?[0] as usize;
        for k in 0..n {
            let (ln, l) = lines[p + 1 + k];
            let mut it = l.splitn(3, ' ');
            let dim = it.next().and_then(|t| t.parse().ok());
            let tag = it.next().and_then(|t| t.parse().ok());
            let name = it.next().map(|t| t.trim().trim_matches('"').to_string());
            match (dim, tag, name) {
                (Some(d), Some(t), Some(nm)) => {
                    names.insert((d, t), nm);
                }
                _ => return Err(syntax(ln, "a physical name is 'dim tag \"name\"'".into())),
            }
        }
    }
    // entities: (dim, tag) -> first physical tag
    let mut physical: HashMap<(usize, usize), usize> = HashMap::new();
    let e0 = section("$Entities")?;
    let counts = nums(lines[e0].0, lines[e0].1)?;
    if counts.len() < 4 {
        return Err(syntax(lines[e0].0, "four entity counts expected".into()));
    }
    let mut row = e0 + 1;
    for dim in 0..4 {
        for _ in 0..counts[dim] as usize {
            let (ln, l) = lines[row];
            let v = nums(ln, l)?;
            // points: tag x y z nphys ...; others: tag 6 box values nphys ...
            let at = if dim == 0 { 4 } else { 7 };
            if v.len() <= at {
                return Err(syntax(ln, "entity line too short".into()));
            }
            let np = v[at] as usize;
            if np > 0 && v.len() > at + 1 {
                physical.insert((dim, v[0] as usize), v[at + 1].abs() as usize);
            }
            row += 1;
        }
    }
    // nodes
    let n0 = section("$Nodes")?;
    let head = nums(lines[n0].0, lines[n0].1)?;
    let blocks = head[0] as usize;
    let mut index: HashMap<usize, usize> = HashMap::new();
    let mut coords: Vec<[f64; 3]> = Vec::new();
    let mut row = n0 + 1;
    for _ in 0..blocks {
        let b = nums(lines[row].0, lines[row].1)?;
        let n = b[3] as usize;
        for k in 0..n {
            let tag = nums(lines[row + 1 + k].0, lines[row + 1 + k].1)?[0] as usize;
            let (ln, l) = lines[row + 1 + n + k];
            let x = nums(ln, l)?;
            if x.len() < 3 {
                return Err(syntax(ln, "a node needs x y z".into()));
            }
            index.insert(tag, coords.len());
            coords.push([x[0], x[1], x[2]]);
        }
        row += 1 + 2 * n;
    }
    // elements, grouped by dimension with the (dim, entity) they lie on
    let el0 = section("$Elements")?;
    let blocks = nums(lines[el0].0, lines[el0].1)?[0] as usize;
    let mut by_dim: Vec<Vec<GmshElement>> = vec![Vec::new(); 4];
    let mut row = el0 + 1;
    for _ in 0..blocks {
        let (ln, l) = lines[row];
        let b = nums(ln, l)?;
        let (dim, ent, etype, n) = (b[0] as usize, b[1] as usize, b[2] as usize, b[3] as usize);
        let nn = match etype {
            1 => 2,
            2 => 3,
            3 => 4,
            4 => 4,
            5 => 8,
            6 => 6,
            7 => 5,
            15 => 1,
            t => return Err(syntax(ln, format!("unsupported element type {t}"))),
        };
        for k in 0..n {
            let (ln2, l2) = lines[row + 1 + k];
            let v = nums(ln2, l2)?;
            if v.len() < 1 + nn {
                return Err(syntax(ln2, format!("element needs {nn} nodes")));
            }
            let ids = v[1..=nn]
                .iter()
                .map(|t| {
                    index
                        .get(&(*t as usize))
                        .copied()
                        .ok_or_else(|| syntax(ln2, format!("unknown node {t}")))
                })
                .collect::<Result<Vec<_>, _>>()?;
            by_dim[dim].push(((dim, ent), ids, ln2));
        }
        row += 1 + n;
    }
    let dim = (2..4)
        .rev()
        .find(|&d| !by_dim[d].is_empty())
        .ok_or_else(|| syntax(lines[el0].0, "no 2-D or 3-D elements".into()))?;
    let known: Vec<String> = markers.keys().cloned().collect();
    let mut bfaces = Vec::new();
    for (key, ids, ln) in &by_dim[dim - 1] {
        let name = physical
            .get(key)
            .and_then(|p| names.get(&(key.0, *p)))
            .ok_or_else(|| {
                syntax(
                    *ln,
                    format!("boundary element on entity {key:?} without a physical name"),
                )
            })?;
        let kind = *markers.get(name).ok_or_else(|| ReadError::UnknownMarker {
            marker: name.clone(),
            known: known.clone(),
        })?;
        bfaces.push((ids.clone(), kind));
    }
    let cells: Vec<Vec<usize>> = by_dim[dim].iter().map(|(_, ids, _)| ids.clone()).collect();
    if dim == 2 {
        // keep only the nodes of the plane (z = 0 expected) and extrude
        let nodes2: Vec<[f64; 2]> = coords.iter().map(|p| [p[0], p[1]]).collect();
        extrude(&nodes2, &cells, &bfaces, dz)
    } else {
        from_cells(coords, cells, bfaces)
    }
}

/// Writes a one-cell-thick extruded O-mesh (as built by [`crate::mesh::o_mesh`]) as a 2-D SU2
/// mesh with markers "wall" and "farfield": the plane z = 0 of its quadrilaterals.
pub fn write_su2_2d(mesh: &Mesh) -> String {
    let per_layer = mesh.nodes.len() / 2;
    let mut s = format!("NDIME= 2\nNELEM= {}\n", mesh.cells.len());
    for (i, c) in mesh.cells.iter().enumerate() {
        s += &format!("9 {} {} {} {} {i}\n", c[0], c[1], c[2], c[3]);
    }
    s += &format!("NPOIN= {per_layer}\n");
    for (i, p) in mesh.nodes[..per_layer].iter().enumerate() {
        s += &format!("{:.17e} {:.17e} {i}\n", p[0], p[1]);
    }
    let mut marks: Vec<(String, Vec<[usize; 2]>)> = Vec::new();
    for (name, kind) in [("wall", Boundary::Wall), ("farfield", Boundary::FarField)] {
        let edges = mesh
            .faces
            .iter()
            .filter(|f| f.right == Side::Boundary(kind))
            .map(|f| {
                let bottom: Vec<usize> =
                    f.nodes.iter().copied().filter(|&n| n < per_layer).collect();
                [bottom[0], bottom[1]]
            })
            .collect();
        marks.push((name.into(), edges));
    }
    s += &format!("NMARK= {}\n", marks.len());
    for (name, edges) in marks {
        s += &format!("MARKER_TAG= {name}\nMARKER_ELEMS= {}\n", edges.len());
        for e in edges {
            s += &format!("3 {} {}\n", e[0], e[1]);
        }
    }
    s
}

/// Writes a 3-D mesh in the SU2 native format: its cells (tetrahedra, pyramids, prisms and
/// hexahedra by node count, in the VTK node order SU2 shares) and its boundary faces under the
/// markers "wall", "farfield" and "symmetry" (only those present). [`read_su2`] reads it back.
pub fn write_su2(mesh: &Mesh) -> String {
    use std::fmt::Write;
    let mut s = format!("NDIME= 3\nNELEM= {}\n", mesh.cells.len());
    for (i, c) in mesh.cells.iter().enumerate() {
        let kind = match c.len() {
            4 => 10,
            5 => 14,
            6 => 13,
            _ => 12,
        };
        let _ = write!(s, "{kind}");
        for n in c {
            let _ = write!(s, " {n}");
        }
        let _ = writeln!(s, " {i}");
    }
    let _ = writeln!(s, "NPOIN= {}", mesh.nodes.len());
    for (i, p) in mesh.nodes.iter().enumerate() {
        let _ = writeln!(s, "{:.17e} {:.17e} {:.17e} {i}", p[0], p[1], p[2]);
    }
    let marks: Vec<(&str, Vec<&Vec<usize>>)> = [
        ("wall", Boundary::Wall),
        ("farfield", Boundary::FarField),
        ("symmetry", Boundary::Symmetry),
    ]
    .into_iter()
    .map(|(name, kind)| {
        let faces = mesh
            .faces
            .iter()
            .filter(|f| f.right == Side::Boundary(kind))
            .map(|f| &f.nodes)
            .collect::<Vec<_>>();
        (name, faces)
    })
    .filter(|(_, faces)| !faces.is_empty())
    .collect();
    let _ = writeln!(s, "NMARK= {}", marks.len());
    for (name, faces) in marks {
        let _ = writeln!(s, "MARKER_TAG= {name}\nMARKER_ELEMS= {}", faces.len());
        for f in faces {
            let _ = write!(s, "{}", if f.len() == 3 { 5 } else { 9 });
            for n in f {
                let _ = write!(s, " {n}");
            }
            s.push('\n');
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::o_mesh;

    fn markers() -> HashMap<String, Boundary> {
        [
            ("wall".to_string(), Boundary::Wall),
            ("farfield".to_string(), Boundary::FarField),
        ]
        .into_iter()
        .collect()
    }

    /// The O-mesh about an ellipse (semi-axes 0.5 and 0.3) the round-trip tests write and read.
    fn ellipse_mesh(n_around: usize, n_radial: usize) -> Mesh {
        o_mesh(
            &|t| {
                let a = 2.0 * std::f64::consts::PI * t;
                [0.5 * a.cos(), 0.3 * a.sin()]
            },
            n_around,
            n_radial,
            8.0,
            0.05,
            0.1,
        )
    }

    /// An O-mesh written as 2-D SU2 and read back has the same volumes, closed cells, the same
    /// boundary faces, and passes the mesh checks.
    #[test]
    fn su2_round_trip() {
        let m = ellipse_mesh(16, 5);
        let text = write_su2_2d(&m);
        let r = read_su2(&text, &markers(), 0.1).unwrap();
        assert_eq!(r.check(), Ok(()));
        assert_eq!(r.n_cells, m.n_cells);
        let (va, vb) = (m.volumes(), r.volumes());
        for (a, b) in va.iter().zip(&vb) {
            assert!((a - b).abs() < 1e-13 * a);
        }
        for kind in [Boundary::Wall, Boundary::FarField, Boundary::Symmetry] {
            let count = |mm: &Mesh| {
                mm.faces
                    .iter()
                    .filter(|f| f.right == Side::Boundary(kind))
                    .count()
            };
            assert_eq!(count(&m), count(&r), "{kind:?}");
        }
    }

    /// Mixed 3-D cells: a unit cube split into a hexahedron-free set of two prisms, and a
    /// tetrahedron plus a pyramid, each closed with positive volume summing to the cube's.
    #[test]
    fn prisms_tets_and_pyramids() {
        let nodes = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0],
        ];
        // two prisms (triangles 0-1-2 and 0-2-3 extruded)
        let cells = vec![vec![0, 1, 2, 4, 5, 6], vec![0, 2, 3, 4, 6, 7]];
        let outer = vec![
            (vec![0, 1, 2], Boundary::FarField),
            (vec![0, 2, 3], Boundary::FarField),
            (vec![4, 5, 6], Boundary::FarField),
            (vec![4, 6, 7], Boundary::FarField),
            (vec![0, 1, 5, 4], Boundary::Wall),
            (vec![1, 2, 6, 5], Boundary::Wall),
            (vec![2, 3, 7, 6], Boundary::Wall),
            (vec![3, 0, 4, 7], Boundary::Wall),
        ];
        let m = from_cells(nodes.clone(), cells, outer).unwrap();
        assert_eq!(m.check(), Ok(()));
        assert!((m.volumes().iter().sum::<f64>() - 1.0).abs() < 1e-14);
        // a pyramid on the bottom face with apex at the centre, and the missing faces as markers
        let mut n2 = nodes[..4].to_vec();
        n2.push([0.5, 0.5, 0.5]);
        let tet_and_pyr = from_cells(
            {
                let mut n = n2.clone();
                n.push([0.5, 0.5, -0.5]);
                n
            },
            vec![vec![0, 1, 2, 3, 4], vec![0, 1, 2, 5]],
            vec![],
        );
        // the tetrahedron does not share a whole face with the pyramid: a clear error
        assert!(matches!(tet_and_pyr, Err(ReadError::Topology(_))));
        let pyr = from_cells(
            n2,
            vec![vec![0, 1, 2, 3, 4]],
            vec![
                (vec![0, 3, 2, 1], Boundary::Wall),
                (vec![0, 1, 4], Boundary::FarField),
                (vec![1, 2, 4], Boundary::FarField),
                (vec![2, 3, 4], Boundary::FarField),
                (vec![3, 0, 4], Boundary::FarField),
            ],
        )
        .unwrap();
        assert!((pyr.volumes()[0] - 1.0 / 6.0).abs() < 1e-15);
    }

    /// The same O-mesh as a Gmsh 4.1 file (one surface, wall and far-field curves with physical
    /// names) reads back to the same volumes and boundaries; an unmapped physical name is an error.
    #[test]
    fn gmsh_round_trip() {
        let m = ellipse_mesh(12, 4);
        let per_layer = m.nodes.len() / 2;
        let mut g = String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n1 1 \"wall\"\n1 2 \"farfield\"\n$EndPhysicalNames\n");
        g += "$Entities\n0 2 1 0\n1 -1 -1 0 1 1 0 1 1 0\n2 -8 -8 0 8 8 0 1 2 0\n1 -8 -8 0 8 8 0 0 2 1 2\n$EndEntities\n";
        g += &format!("$Nodes\n1 {per_layer} 1 {per_layer}\n2 1 0 {per_layer}\n");
        for i in 0..per_layer {
            g += &format!("{}\n", i + 1);
        }
        for p in &m.nodes[..per_layer] {
            g += &format!("{:.17e} {:.17e} 0\n", p[0], p[1]);
        }
        g += "$EndNodes\n";
        let edges = |kind| -> Vec<[usize; 2]> {
            m.faces
                .iter()
                .filter(|f| f.right == Side::Boundary(kind))
                .map(|f| {
                    let b: Vec<usize> =
                        f.nodes.iter().copied().filter(|&n| n < per_layer).collect();
                    [b[0] + 1, b[1] + 1]
                })
                .collect()
        };
        let (wall, far) = (edges(Boundary::Wall), edges(Boundary::FarField));
        let total = wall.len() + far.len() + m.cells.len();
        g += &format!("$Elements\n3 {total} 1 {total}\n");
        let mut tag = 1;
        for (curve, list) in [(1, &wall), (2, &far)] {
            g += &format!("1 {curve} 1 {}\n", list.len());
            for e in list.iter() {
                g += &format!("{tag} {} {}\n", e[0], e[1]);
                tag += 1;
            }
        }
        g += &format!("2 1 3 {}\n", m.cells.len());
        for c in &m.cells {
            g += &format!(
                "{tag} {} {} {} {}\n",
                c[0] + 1,
                c[1] + 1,
                c[2] + 1,
                c[3] + 1
            );
            tag += 1;
        }
        g += "$EndElements\n";
        let r = read_gmsh(&g, &markers(), 0.1).unwrap();
        assert_eq!(r.check(), Ok(()));
        let (va, vb) = (m.volumes(), r.volumes());
        assert!((va.iter().sum::<f64>() - vb.iter().sum::<f64>()).abs() < 1e-13);
        for kind in [Boundary::Wall, Boundary::FarField, Boundary::Symmetry] {
            let count = |mm: &Mesh| {
                mm.faces
                    .iter()
                    .filter(|f| f.right == Side::Boundary(kind))
                    .count()
            };
            assert_eq!(count(&m), count(&r), "{kind:?}");
        }
        let renamed = g.replace("\"farfield\"", "\"inlet\"");
        match read_gmsh(&renamed, &markers(), 0.1) {
            Err(ReadError::UnknownMarker { marker, .. }) => assert_eq!(marker, "inlet"),
            other => panic!("{other:?}"),
        }
    }

    /// Unknown markers and malformed files are errors with the marker name or the line number.
    #[test]
    fn bad_files() {
        let m = o_mesh(
            &|t| {
                let a = 2.0 * std::f64::consts::PI * t;
                [0.5 * a.cos(), 0.5 * a.sin()]
            },
            8,
            2,
            4.0,
            0.2,
            0.1,
        );
        let text = write_su2_2d(&m).replace("MARKER_TAG= farfield", "MARKER_TAG= outlet");
        match read_su2(&text, &markers(), 0.1) {
            Err(ReadError::UnknownMarker { marker, .. }) => assert_eq!(marker, "outlet"),
            other => panic!("{other:?}"),
        }
        let text = write_su2_2d(&m).replacen("9 ", "9 x ", 1);
        let e = read_su2(&text, &markers(), 0.1).unwrap_err();
        assert!(matches!(e, ReadError::Syntax { line: 3, .. }), "{e:?}");
        // a boundary edge left out: the free face has no marker
        let text = write_su2_2d(&m);
        let cut = text.replace("MARKER_ELEMS= 8\n3 ", "MARKER_ELEMS= 7\n%3 ");
        let e = read_su2(&cut, &markers(), 0.1).unwrap_err();
        assert!(e.to_string().contains("no marker"), "{e}");
    }
}
