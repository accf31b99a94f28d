//! Where a figure's text and data land: a plotters backend that draws nothing but records the box
//! of every text it is given (the same layout, anchor and rotation the real backends use), every
//! polyline and dot, and every legend box (a filled rectangle framed at once by an unfilled one of
//! the same corners), so that a test can find labels drawn over each other and legends over data.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters_backend::{
    text_anchor::{HPos, VPos},
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingErrorKind,
};

/// A text and its box in pixels: left, top, right, bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct TextBox {
    pub text: String,
    pub rect: [i32; 4],
}

/// What the recorder saw, in drawing order.
#[derive(Clone, Debug, Default)]
pub struct Drawn {
    pub texts: Vec<TextBox>,
    /// Polylines and dots (a dot: one point), each with its place in the drawing order.
    pub marks: Vec<(usize, Vec<(i32, i32)>)>,
    /// Legend boxes (left, top, right, bottom), each with its place in the drawing order.
    pub legends: Vec<(usize, [i32; 4])>,
    /// The last filled rectangle and its place (a legend box if a frame follows).
    last_fill: Option<(usize, [i32; 4])>,
    order: usize,
}

/// The recording backend (the drawing area owns it; what it saw is shared with the caller).
struct Recorder {
    size: (u32, u32),
    drawn: std::rc::Rc<std::cell::RefCell<Drawn>>,
}

impl DrawingBackend for Recorder {
    type ErrorType = std::io::Error;

    fn get_size(&self) -> (u32, u32) {
        self.size
    }
    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        Ok(())
    }
    fn present(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        Ok(())
    }
    fn draw_pixel(
        &mut self,
        _point: BackendCoord,
        _color: BackendColor,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        Ok(())
    }
    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        if style.color().alpha > 0.0 {
            let mut d = self.drawn.borrow_mut();
            d.order += 1;
            let o = d.order;
            d.marks.push((o, path.into_iter().collect()));
        }
        Ok(())
    }
    fn draw_circle<S: BackendStyle>(
        &mut self,
        center: BackendCoord,
        _radius: u32,
        style: &S,
        _fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        if style.color().alpha > 0.0 {
            let mut d = self.drawn.borrow_mut();
            d.order += 1;
            let o = d.order;
            d.marks.push((o, vec![center]));
        }
        Ok(())
    }
    fn draw_rect<S: BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        _style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let rect = [upper_left.0, upper_left.1, bottom_right.0, bottom_right.1];
        let mut d = self.drawn.borrow_mut();
        d.order += 1;
        let o = d.order;
        if fill {
            d.last_fill = Some((o, rect));
        } else if let Some((fo, fr)) = d.last_fill.take() {
            if fr == rect && fo + 1 == o {
                d.legends.push((fo, rect));
            }
        }
        Ok(())
    }
    fn draw_text<S: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &S,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        if text.trim().is_empty() || style.color().alpha == 0.0 {
            return Ok(());
        }
        let ((x0, y0), (x1, y1)) = style
            .layout_box(text)
            .map_err(|e| DrawingErrorKind::FontError(Box::new(e)))?;
        let (w, h) = (x1 - x0, y1 - y0);
        let dx = match style.anchor().h_pos {
            HPos::Left => 0,
            HPos::Right => -w,
            HPos::Center => -w / 2,
        };
        let dy = match style.anchor().v_pos {
            VPos::Top => 0,
            VPos::Center => -h / 2,
            VPos::Bottom => -h,
        };
        let t = style.transform();
        let (ax, ay) = t.transform(dx, dy);
        let (bx, by) = t.transform(dx + w, dy + h);
        self.drawn.borrow_mut().texts.push(TextBox {
            text: text.to_string(),
            rect: [
                pos.0 + ax.min(bx),
                pos.1 + ay.min(by),
                pos.0 + ax.max(bx),
                pos.1 + ay.max(by),
            ],
        });
        Ok(())
    }
}

/// Everything `fig` draws at its own size, as the recorder saw it.
pub fn drawn(fig: &impl super::Figure) -> anyhow::Result<Drawn> {
    super::register_fonts();
    let drawn = std::rc::Rc::new(std::cell::RefCell::new(Drawn::default()));
    let area: DrawingArea<Recorder, Shift> = Recorder {
        size: fig.size(),
        drawn: drawn.clone(),
    }
    .into_drawing_area();
    fig.draw(&area)?;
    drop(area);
    let out = drawn.borrow().clone();
    Ok(out)
}

/// Every text box of `fig` as drawn at its own size.
pub fn text_boxes(fig: &impl super::Figure) -> anyhow::Result<Vec<TextBox>> {
    Ok(drawn(fig)?.texts)
}

/// Whether the segment a–b passes through the open interior of `r` (Liang–Barsky clipping).
fn segment_enters(a: (i32, i32), b: (i32, i32), r: [i32; 4]) -> bool {
    let (x0, y0) = (a.0 as f64, a.1 as f64);
    let (dx, dy) = ((b.0 - a.0) as f64, (b.1 - a.1) as f64);
    let (l, t, rr, bt) = (
        r[0] as f64 + 0.5,
        r[1] as f64 + 0.5,
        r[2] as f64 - 0.5,
        r[3] as f64 - 0.5,
    );
    let (mut u0, mut u1) = (0.0f64, 1.0f64);
    for (p, q) in [(-dx, x0 - l), (dx, rr - x0), (-dy, y0 - t), (dy, bt - y0)] {
        if p == 0.0 {
            if q < 0.0 {
                return false;
            }
        } else {
            let u = q / p;
            if p < 0.0 {
                u0 = u0.max(u);
            } else {
                u1 = u1.min(u);
            }
        }
    }
    u0 < u1
}

/// A legend box (left, top, right, bottom) and the first point of a mark it hides or cuts.
pub type LegendOverData = ([i32; 4], (i32, i32));

/// Data a legend box hides or cuts: every mark drawn before the box with a point or segment in
/// it (the box's white fill covers it), and every line drawn after it that crosses its edge (a
/// legend's own keys lie wholly inside it). Returns (legend box, the mark's first point) pairs.
pub fn legends_over_data(fig: &impl super::Figure) -> anyhow::Result<Vec<LegendOverData>> {
    let d = drawn(fig)?;
    let inside = |p: &(i32, i32), r: [i32; 4]| p.0 > r[0] && p.0 < r[2] && p.1 > r[1] && p.1 < r[3];
    let mut out = Vec::new();
    for &(lo, r) in &d.legends {
        for (mo, pts) in &d.marks {
            let Some(first) = pts.first() else { continue };
            let hit = if *mo < lo {
                pts.iter().any(|p| inside(p, r))
                    || pts.windows(2).any(|s| segment_enters(s[0], s[1], r))
            } else {
                !pts.iter().all(|p| inside(p, r))
                    && pts.windows(2).any(|s| segment_enters(s[0], s[1], r))
            };
            if hit {
                out.push((r, *first));
            }
        }
    }
    Ok(out)
}

/// Pairs of texts of `fig` whose boxes overlap by more than `slack` pixels both ways.
pub fn overlapping_text(
    fig: &impl super::Figure,
    slack: i32,
) -> anyhow::Result<Vec<(TextBox, TextBox)>> {
    let boxes = text_boxes(fig)?;
    let mut out = Vec::new();
    for (i, a) in boxes.iter().enumerate() {
        for b in &boxes[i + 1..] {
            let ox = a.rect[2].min(b.rect[2]) - a.rect[0].max(b.rect[0]);
            let oy = a.rect[3].min(b.rect[3]) - a.rect[1].max(b.rect[1]);
            if ox > slack && oy > slack {
                out.push((a.clone(), b.clone()));
            }
        }
    }
    Ok(out)
}
