//! The lifting surfaces of a Nastran model (CAERO1 panels as DLM surfaces, in the aerodynamic
//! coordinate system AERO.ACSID whose x axis is the flow) and the splines that move their boxes
//! with the structure: the model's modes sampled on the DLM's points.

use super::bulk::{BulkData, SplineKind};
use super::spline::{beam, infinite_plate, BeamAttachment, SplineRows};
use super::structure::{Frame, RealModes, Structure};
use super::NastranError;
use faer::Mat;
use gustkit_core::ModalSurface;
use gustkit_dlm::{Dlm, Spacing, SurfaceSpec, Symmetry};
use std::collections::BTreeMap;

type R<T> = Result<T, NastranError>;

/// The DLM of a Nastran model's CAERO1 panels with its reference values.
pub struct LiftingSurfaces {
    pub dlm: Dlm,
    /// The Nastran box id of every DLM box, in the DLM's order (chordwise fastest, as Nastran
    /// numbers them from the CAERO1's EID).
    pub box_ids: Vec<u32>,
    /// The CAERO1 of every box.
    pub box_caero: Vec<u32>,
    /// Chordwise boxes of every CAERO1 (by its id).
    pub n_chord: BTreeMap<u32, u32>,
    /// The aerodynamic frame (ACSID): the DLM's coordinates are in it.
    pub frame: Frame,
    /// Reference semichord REFC/2 and density RHOREF (the model's units).
    pub b_ref: f64,
    pub rho_ref: f64,
}

/// The DLM of the CAERO1 panels (uniform divisions or AEFACT fractions), with AERO's symmetry.
pub fn lifting_surfaces(b: &BulkData, s: &Structure) -> R<LiftingSurfaces> {
    let aero = b.aero.as_ref().ok_or_else(|| {
        NastranError::model("bulk data", "has no AERO card: a dynamic aeroelastic analysis needs its reference chord, density and coordinate system".into())
    })?;
    let frame = *s.frames.get(&aero.acsid).ok_or_else(|| {
        NastranError::model(
            "AERO",
            format!(
                "ACSID {} is not a coordinate system of the model",
                aero.acsid
            ),
        )
    })?;
    if aero.symxy != 0 {
        return Err(NastranError::model(
            "AERO",
            "SYMXY (ground effect) is not modelled: set it to 0".into(),
        ));
    }
    let symmetry = match aero.symxz {
        0 => Symmetry::None,
        1 => Symmetry::Symmetric,
        -1 => Symmetry::Antisymmetric,
        v => {
            return Err(NastranError::model(
                "AERO",
                format!("SYMXZ must be −1, 0 or 1 (got {v})"),
            ))
        }
    };
    // basic → aerodynamic frame
    let to_aero = |p: [f64; 3]| -> [f64; 3] {
        let d = [
            p[0] - frame.origin[0],
            p[1] - frame.origin[1],
            p[2] - frame.origin[2],
        ];
        std::array::from_fn(|i| frame.axes[i].iter().zip(d).map(|(a, b)| a * b).sum())
    };
    let mut surfaces = Vec::new();
    let mut box_ids = Vec::new();
    let mut box_caero = Vec::new();
    let mut n_chord = BTreeMap::new();
    for c in b.caero1.values() {
        let what = format!("CAERO1 {}", c.id);
        if !b.paero1.contains_key(&c.pid) {
            return Err(NastranError::model(
                &what,
                format!(
                    "refers to PAERO1 {}, which the model does not define",
                    c.pid
                ),
            ));
        }
        if c.igid <= 0 {
            return Err(NastranError::model(
                &what,
                format!("IGID must be positive (got {})", c.igid),
            ));
        }
        // divisions: a count (uniform) or an AEFACT of edge fractions (LSPAN, LCHORD win)
        let division = |count: Option<u32>, list: Option<u32>, field: &str| -> R<(u32, Spacing)> {
            match list {
                Some(id) => {
                    let f = b.aefact.get(&id).ok_or_else(|| {
                        NastranError::model(
                            &what,
                            format!("{field} names AEFACT {id}, which the model does not define"),
                        )
                    })?;
                    if f.len() < 2 {
                        return Err(NastranError::model(
                            &what,
                            format!("AEFACT {id} ({field}) needs at least two fractions"),
                        ));
                    }
                    Ok((f.len() as u32 - 1, Spacing::Fractions(f.clone())))
                }
                None => Ok((count.unwrap_or(1), Spacing::Uniform)),
            }
        };
        let (ns, span_spacing) = division(c.nspan, c.lspan, "LSPAN")?;
        let (nc, chord_spacing) = division(c.nchord, c.lchord, "LCHORD")?;
        let cp = *s.frames.get(&c.cp).ok_or_else(|| {
            NastranError::model(
                &what,
                format!("CP {} is not a coordinate system of the model", c.cp),
            )
        })?;
        let spec = SurfaceSpec {
            name: what.clone(),
            p1: to_aero(cp.to_basic(c.p1)),
            c1: c.x12,
            p4: to_aero(cp.to_basic(c.p4)),
            c4: c.x43,
            n_chord: nc as usize,
            n_span: ns as usize,
            chord_spacing,
            span_spacing,
        };
        n_chord.insert(c.id, nc);
        for k in 0..(ns * nc) {
            box_ids.push(c.id + k);
            box_caero.push(c.id);
        }
        surfaces.push(spec);
    }
    if surfaces.is_empty() {
        return Err(NastranError::model(
            "bulk data",
            "has no CAERO1 panel".into(),
        ));
    }
    let mut sorted = box_ids.clone();
    sorted.sort_unstable();
    if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
        return Err(NastranError::model("CAERO1", format!("box id {} belongs to two panels: space the panels' EIDs by at least their box counts", w[0])));
    }
    let n_surfaces = surfaces.len();
    let mut dlm =
        Dlm::new(surfaces, symmetry).map_err(|e| NastranError::model("CAERO1", e.to_string()))?;
    // a Nastran model's panels are fixed: its reverse mode needs no geometry gradient
    for si in 0..n_surfaces {
        dlm.set_active_geometry(si, &[]);
    }
    Ok(LiftingSurfaces {
        dlm,
        box_ids,
        box_caero,
        n_chord,
        frame,
        b_ref: 0.5 * aero.refc,
        rho_ref: aero.rhoref,
    })
}

/// The splines' matrix from the g-set to every DLM point (the control points, then the
/// doublet points, as the DLM lists them): normal displacement and streamwise slope. Each box
/// takes its motion from the one spline that names it; a box no spline names does not move
/// (Nastran's behaviour), which is reported.
pub fn spline_rows(
    b: &BulkData,
    s: &Structure,
    surf: &LiftingSurfaces,
) -> R<(SplineRows, Vec<u32>)> {
    use gustkit_core::Aerodynamics;
    let n_boxes = surf.box_ids.len();
    let owners: Vec<usize> = (0..2 * n_boxes).map(|p| p % n_boxes).collect();
    spline_rows_at(b, s, surf, &surf.dlm.surface().points, &owners)
}

/// The splines' matrix from the g-set to any points of the panels (aerodynamic frame), each
/// moved by the spline of the box that owns it (`owners`, DLM box indices): what another
/// fidelity's surface points (the LFD's wall nodes on the planform) take from the model.
pub fn spline_rows_at(
    b: &BulkData,
    s: &Structure,
    surf: &LiftingSurfaces,
    points: &[[f64; 3]],
    owners: &[usize],
) -> R<(SplineRows, Vec<u32>)> {
    use gustkit_core::Aerodynamics;
    debug_assert_eq!(points.len(), owners.len());
    let n_boxes = surf.box_ids.len();
    let box_points = &surf.dlm.surface().points;
    let normals = &surf.dlm.surface().normals;
    // the points each box owns
    let mut owned: Vec<Vec<usize>> = vec![Vec::new(); n_boxes];
    for (p, &o) in owners.iter().enumerate() {
        owned[o].push(p);
    }
    let index: BTreeMap<u32, usize> = surf
        .box_ids
        .iter()
        .enumerate()
        .map(|(i, &id)| (id, i))
        .collect();
    let ng = s.k_gg.nrows();
    let mut value = Mat::<f64>::zeros(points.len(), ng);
    let mut slope = Mat::<f64>::zeros(points.len(), ng);
    let mut owner: Vec<Option<u32>> = vec![None; n_boxes];
    let flow = surf.frame.axes[0];
    for sp in b.splines.values() {
        let what = format!(
            "{} {}",
            match sp.kind {
                SplineKind::InfinitePlate => "SPLINE1",
                SplineKind::Beam => "SPLINE2",
                SplineKind::ThinPlate => "SPLINE4",
            },
            sp.id
        );
        let caero = b.caero1.get(&sp.caero).ok_or_else(|| {
            NastranError::model(
                &what,
                format!(
                    "refers to CAERO1 {}, which the model does not define",
                    sp.caero
                ),
            )
        })?;
        let boxes: Vec<u32> = match (sp.boxes, sp.aelist) {
            // BOX1 and BOX2 are opposite corners of a rectangle of boxes of the panel
            (Some((b1, b2)), _) => {
                let nc = surf.n_chord[&caero.id];
                let at = |id: u32| -> R<(u32, u32)> {
                    let k = id
                        .checked_sub(caero.id)
                        .filter(|_| {
                            index.contains_key(&id) && surf.box_caero[index[&id]] == caero.id
                        })
                        .ok_or_else(|| {
                            NastranError::model(
                                &what,
                                format!("names box {id}, which CAERO1 {} does not have", caero.id),
                            )
                        })?;
                    Ok((k % nc, k / nc))
                };
                let ((i1, j1), (i2, j2)) = (at(b1)?, at(b2)?);
                if i2 < i1 || j2 < j1 {
                    return Err(NastranError::model(&what, format!("BOX1 {b1} and BOX2 {b2} are not the first and last corners of a rectangle of boxes")));
                }
                (j1..=j2)
                    .flat_map(|j| (i1..=i2).map(move |i| caero.id + i + nc * j))
                    .collect()
            }
            (None, Some(list)) => b.aelist.get(&list).cloned().ok_or_else(|| {
                NastranError::model(
                    &what,
                    format!("refers to AELIST {list}, which the model does not define"),
                )
            })?,
            _ => unreachable!("a spline names boxes or an AELIST"),
        };
        let mut own = Vec::new();
        for id in boxes {
            let &i = index.get(&id).ok_or_else(|| {
                NastranError::model(&what, format!("names box {id}, which no CAERO1 has"))
            })?;
            if surf.box_caero[i] != caero.id {
                return Err(NastranError::model(
                    &what,
                    format!(
                        "names box {id}, which belongs to CAERO1 {}, not {}",
                        surf.box_caero[i], caero.id
                    ),
                ));
            }
            if let Some(other) = owner[i] {
                return Err(NastranError::model(
                    &what,
                    format!("names box {id}, which spline {other} moves already"),
                ));
            }
            owner[i] = Some(sp.id);
            own.push(i);
        }
        let set = b.set1.get(&sp.setg).ok_or_else(|| {
            NastranError::model(
                &what,
                format!(
                    "refers to SET1 {}, which the model does not define",
                    sp.setg
                ),
            )
        })?;
        let grids: Vec<usize> = set
            .iter()
            .map(|g| {
                s.index.get(g).copied().ok_or_else(|| {
                    NastranError::model(
                        &what,
                        format!(
                            "SET1 {} names grid {g}, which the model does not define",
                            sp.setg
                        ),
                    )
                })
            })
            .collect::<R<_>>()?;
        if sp.usage == "FORCE" {
            continue;
        }
        // the spline's points (those its boxes own), in basic
        let rows_of: Vec<usize> = own.iter().flat_map(|&i| owned[i].iter().copied()).collect();
        if rows_of.is_empty() {
            continue;
        }
        let pts: Vec<[f64; 3]> = rows_of
            .iter()
            .map(|&r| surf.frame.to_basic(points[r]))
            .collect();
        let normal = surf.frame.rotate(normals[own[0]]);
        let rows = match sp.kind {
            SplineKind::Beam => {
                let frame = *s.frames.get(&sp.cid).ok_or_else(|| {
                    NastranError::model(
                        &what,
                        format!("CID {} is not a coordinate system of the model", sp.cid),
                    )
                })?;
                let flex = |v: f64| if v < 0.0 { None } else { Some(v) };
                let att = BeamAttachment {
                    dz: sp.dz,
                    dthx: flex(sp.dthx),
                    dthy: flex(sp.dthy),
                    dtor: sp.dtor,
                };
                beam(s, &grids, &frame, normal, flow, att, &pts, &what)?
            }
            SplineKind::InfinitePlate | SplineKind::ThinPlate => {
                if sp.dz != 0.0 {
                    return Err(NastranError::model(
                        &what,
                        format!("DZ = {} (smoothing) is not read: give 0", sp.dz),
                    ));
                }
                // the plane of the panel: flow, the in-plane spanwise direction, the normal
                let y = [
                    normal[1] * flow[2] - normal[2] * flow[1],
                    normal[2] * flow[0] - normal[0] * flow[2],
                    normal[0] * flow[1] - normal[1] * flow[0],
                ];
                let origin = surf.frame.to_basic(box_points[own[0]]);
                infinite_plate(s, &grids, origin, [flow, y, normal], &pts, &what)?
            }
        };
        for (k, &r) in rows_of.iter().enumerate() {
            for j in 0..ng {
                value[(r, j)] = rows.value[(k, j)];
                slope[(r, j)] = rows.slope[(k, j)];
            }
        }
    }
    let unmoved: Vec<u32> = owner
        .iter()
        .enumerate()
        .filter(|(_, o)| o.is_none())
        .map(|(i, _)| surf.box_ids[i])
        .collect();
    Ok((SplineRows { value, slope }, unmoved))
}

/// The first `n_modes` modes on the DLM's points: normal displacement and slope along the box
/// normals (in the aerodynamic frame).
pub fn modal_surface(
    surf: &LiftingSurfaces,
    rows: &SplineRows,
    modes: &RealModes,
    n_modes: usize,
) -> ModalSurface {
    use gustkit_core::Aerodynamics;
    modal_surface_on(&surf.dlm.surface().normals, rows, modes, n_modes)
}

/// [`modal_surface`] on any points with their spline rows and the normals their displacement
/// is along.
pub fn modal_surface_on(
    normals: &[[f64; 3]],
    rows: &SplineRows,
    modes: &RealModes,
    n_modes: usize,
) -> ModalSurface {
    let np = normals.len();
    let mut out = ModalSurface::zeros(n_modes, np);
    let ng = rows.value.ncols();
    for m in 0..n_modes {
        for p in 0..np {
            let (mut w, mut wx) = (0.0, 0.0);
            for j in 0..ng {
                let phi = modes.phi_g[(j, m)];
                if phi != 0.0 {
                    w += rows.value[(p, j)] * phi;
                    wx += rows.slope[(p, j)] * phi;
                }
            }
            let n = normals[p];
            out.disp[m][p] = [n[0] * w, n[1] * w, n[2] * w];
            out.disp_x[m][p] = [n[0] * wx, n[1] * wx, n[2] * wx];
        }
    }
    out
}

/// The transpose of [`modal_surface`]: seeds on the modal surface's displacements and slopes to
/// seeds on the g-set shapes (`ng` rows, a column a mode).
pub fn modal_surface_vjp(
    surf: &LiftingSurfaces,
    rows: &SplineRows,
    seed: &ModalSurface,
) -> faer::Mat<f64> {
    use gustkit_core::Aerodynamics;
    modal_surface_vjp_on(&surf.dlm.surface().normals, rows, seed)
}

/// The transpose of [`modal_surface_on`].
pub fn modal_surface_vjp_on(
    normals: &[[f64; 3]],
    rows: &SplineRows,
    seed: &ModalSurface,
) -> faer::Mat<f64> {
    let ng = rows.value.ncols();
    let n_modes = seed.n_modes();
    let mut out = faer::Mat::<f64>::zeros(ng, n_modes);
    for m in 0..n_modes {
        for (p, n) in normals.iter().enumerate() {
            let d = seed.disp[m][p];
            let dx = seed.disp_x[m][p];
            let w_bar = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
            let wx_bar = n[0] * dx[0] + n[1] * dx[1] + n[2] * dx[2];
            if w_bar == 0.0 && wx_bar == 0.0 {
                continue;
            }
            for j in 0..ng {
                out[(j, m)] += rows.value[(p, j)] * w_bar + rows.slope[(p, j)] * wx_bar;
            }
        }
    }
    out
}
