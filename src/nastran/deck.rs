//! A Nastran input file as text: its three sections (executive control up to CEND, case control
//! up to BEGIN BULK, bulk data up to ENDDATA), INCLUDE statements resolved, comments dropped, and
//! the bulk data joined into cards from small-field (8 columns), large-field (`NAME*`, 16
//! columns) and free-field (comma-separated) lines with their continuations.

use super::field::{classify, Value};
use super::NastranError;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Where a card or statement starts: file and 1-based line.
#[derive(Clone, Debug, PartialEq)]
pub struct Source {
    pub file: Arc<PathBuf>,
    pub line: usize,
}

impl std::fmt::Display for Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} line {}", self.file.display(), self.line)
    }
}

/// One physical line of the executive or case control section.
#[derive(Clone, Debug)]
pub struct Statement {
    pub text: String,
    pub source: Source,
}

/// One bulk data entry with its continuations: the name and the data fields numbered as the
/// Quick Reference Guide numbers them across lines (field `p` ≥ 1 is field (p − 1) % 8 + 2 of
/// line (p − 1) / 8 + 1; continuation markers are not data).
#[derive(Clone, Debug)]
pub struct Card {
    pub name: String,
    pub fields: Vec<String>,
    pub source: Source,
}

/// The deepest chain of INCLUDE statements followed (a circle is caught before it).
const MAX_INCLUDE_DEPTH: usize = 16;

/// A read input file.
#[derive(Clone, Debug, Default)]
pub struct Deck {
    pub executive: Vec<Statement>,
    pub case_control: Vec<Statement>,
    pub bulk: Vec<Card>,
    /// Whether the file had an executive section (CEND) and a BEGIN BULK: a bulk-data-only
    /// file (an include) has neither.
    pub has_cend: bool,
    pub has_begin_bulk: bool,
}

#[derive(Clone, Copy, PartialEq)]
enum Section {
    Executive,
    CaseControl,
    Bulk,
    Done,
}

/// A physical line after tab expansion and comment removal, with its source.
struct Line {
    text: String,
    source: Source,
}

impl Deck {
    /// Reads `file` and what it includes.
    pub fn read(file: &Path) -> Result<Self, NastranError> {
        let mut lines = Vec::new();
        let mut stack = Vec::new();
        read_lines(file, None, &mut lines, &mut stack)?;
        Self::from_lines(lines)
    }

    /// Reads deck text as if it came from `file` (INCLUDE statements resolved beside it).
    pub fn from_text(file: &Path, text: &str) -> Result<Self, NastranError> {
        let mut lines = Vec::new();
        let mut stack = vec![file.to_path_buf()];
        split_lines(file, text, &mut lines, &mut stack)?;
        Self::from_lines(lines)
    }

    fn from_lines(lines: Vec<Line>) -> Result<Self, NastranError> {
        let has_cend = lines.iter().any(|l| first_word(&l.text) == "CEND");
        let has_begin_bulk = lines.iter().any(|l| is_begin_bulk(&l.text));
        let mut deck = Deck {
            has_cend,
            has_begin_bulk,
            ..Default::default()
        };
        let mut section = match (has_cend, has_begin_bulk) {
            (true, _) => Section::Executive,
            (false, true) => Section::CaseControl,
            (false, false) => Section::Bulk,
        };
        let mut bulk_lines = Vec::new();
        for line in lines {
            let word = first_word(&line.text);
            match section {
                Section::Executive => {
                    if word == "CEND" {
                        section = Section::CaseControl;
                    } else if !line.text.trim().is_empty() {
                        deck.executive.push(Statement {
                            text: line.text.trim_end().to_string(),
                            source: line.source,
                        });
                    }
                }
                Section::CaseControl => {
                    if is_begin_bulk(&line.text) {
                        section = Section::Bulk;
                    } else if !line.text.trim().is_empty() {
                        deck.case_control.push(Statement {
                            text: line.text.trim_end().to_string(),
                            source: line.source,
                        });
                    }
                }
                Section::Bulk => {
                    if word == "ENDDATA" {
                        section = Section::Done;
                    } else if !line.text.trim().is_empty() {
                        bulk_lines.push(line);
                    }
                }
                Section::Done => {}
            }
        }
        deck.bulk = join_cards(bulk_lines)?;
        Ok(deck)
    }
}

/// `BEGIN BULK` (or `BEGIN BULK` with a superelement or part name, `BEGIN SUPER=…`).
fn is_begin_bulk(text: &str) -> bool {
    let t = text.trim_start().to_ascii_uppercase();
    t.starts_with("BEGIN") && t[5..].trim_start().starts_with("BULK")
}

/// The first word of a line, upper case, ended by a blank, comma, `=` or `(`.
fn first_word(text: &str) -> String {
    text.trim_start()
        .split(|c: char| c.is_whitespace() || c == ',' || c == '=' || c == '(')
        .next()
        .unwrap_or("")
        .to_ascii_uppercase()
}

/// Reads `file` (relative to `from`'s folder when given and it exists there) into `lines`.
fn read_lines(
    file: &Path,
    from: Option<&Source>,
    lines: &mut Vec<Line>,
    stack: &mut Vec<PathBuf>,
) -> Result<(), NastranError> {
    let path = match from {
        Some(src) if file.is_relative() => {
            let beside = src
                .file
                .parent()
                .map(|d| d.join(file))
                .unwrap_or_else(|| file.to_path_buf());
            if beside.exists() {
                beside
            } else {
                file.to_path_buf()
            }
        }
        _ => file.to_path_buf(),
    };
    let err = |reason: String| match from {
        Some(src) => NastranError::at(src, "INCLUDE", reason),
        None => NastranError::file(&path, reason),
    };
    if stack.len() >= MAX_INCLUDE_DEPTH {
        return Err(err(format!(
            "INCLUDE statements nest deeper than {MAX_INCLUDE_DEPTH} files"
        )));
    }
    let canonical = path.canonicalize().unwrap_or_else(|_| path.clone());
    if stack.contains(&canonical) {
        return Err(err(format!(
            "'{}' includes itself (through {})",
            path.display(),
            stack
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(" → ")
        )));
    }
    let bytes =
        std::fs::read(&path).map_err(|e| err(format!("cannot read '{}': {e}", path.display())))?;
    // decks are ASCII; a stray Latin-1 byte in a comment must not stop the reading
    let text = String::from_utf8_lossy(&bytes);
    stack.push(canonical);
    split_lines(&path, &text, lines, stack)?;
    stack.pop();
    Ok(())
}

/// Splits text into lines (tabs expanded to 8-column stops, `$` comments dropped), following
/// INCLUDE statements.
fn split_lines(
    file: &Path,
    text: &str,
    lines: &mut Vec<Line>,
    stack: &mut Vec<PathBuf>,
) -> Result<(), NastranError> {
    let file = Arc::new(file.to_path_buf());
    let mut raw = text.lines().enumerate().peekable();
    while let Some((i, l)) = raw.next() {
        let source = Source {
            file: file.clone(),
            line: i + 1,
        };
        let expanded = expand_tabs(l);
        if first_word(&expanded) == "INCLUDE" {
            // the file name is quoted and may run over several lines
            let mut spec = expanded.trim_start()[7..].to_string();
            while spec.matches('\'').count() == 1 {
                match raw.next() {
                    Some((_, more)) => spec.push_str(more.trim()),
                    None => break,
                }
            }
            let name = spec.trim();
            let name = match (name.find('\''), name.rfind('\'')) {
                (Some(a), Some(b)) if b > a => &name[a + 1..b],
                _ => name.split('$').next().unwrap_or("").trim(),
            };
            if name.is_empty() {
                return Err(NastranError::at(
                    &source,
                    "INCLUDE",
                    "names no file (write INCLUDE 'file.bdf')".into(),
                ));
            }
            read_lines(Path::new(name), Some(&source), lines, stack)?;
            continue;
        }
        let text = match expanded.find('$') {
            Some(0) => continue,
            Some(j) => expanded[..j].to_string(),
            None => expanded,
        };
        if text.trim().is_empty() {
            continue;
        }
        lines.push(Line { text, source });
    }
    Ok(())
}

/// Expands tabs to the next multiple of 8 columns (how Nastran reads a tab in a fixed field).
fn expand_tabs(line: &str) -> String {
    if !line.contains('\t') {
        return line.to_string();
    }
    let mut out = String::with_capacity(line.len() + 16);
    for c in line.chars() {
        if c == '\t' {
            let n = 8 - out.chars().count() % 8;
            out.extend(std::iter::repeat_n(' ', n));
        } else {
            out.push(c);
        }
    }
    out
}

/// How one physical bulk line is laid out.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Format {
    Small,
    Large,
    Free,
}

/// The head (name or continuation marker) and data fields of one physical bulk line.
fn fields_of(text: &str) -> (String, Vec<String>, Format) {
    if text.contains(',') {
        let mut tokens = text.split(',').map(|t| t.trim().to_ascii_uppercase());
        let head = tokens.next().unwrap_or_default();
        let large = head.ends_with('*');
        let per_line = if large { 4 } else { 8 };
        // every (per_line + 1)-th token after the head is a continuation marker slot
        let data = tokens
            .enumerate()
            .filter(|(i, _)| (i + 1) % (per_line + 1) != 0)
            .map(|(_, t)| t)
            .collect();
        return (head, data, Format::Free);
    }
    let chars: Vec<char> = text.chars().collect();
    let column = |a: usize, b: usize| -> String {
        chars
            .get(a.min(chars.len())..b.min(chars.len()))
            .map(|s| s.iter().collect::<String>())
            .unwrap_or_default()
            .trim()
            .to_ascii_uppercase()
    };
    let head = column(0, 8);
    if head.ends_with('*') || head.starts_with('*') {
        let data = (0..4).map(|i| column(8 + 16 * i, 24 + 16 * i)).collect();
        (head, data, Format::Large)
    } else {
        let data = (0..8).map(|i| column(8 + 8 * i, 16 + 8 * i)).collect();
        (head, data, Format::Small)
    }
}

/// Joins physical lines into cards: a line whose head starts with `+` or `*`, or is blank,
/// continues the card before it.
fn join_cards(lines: Vec<Line>) -> Result<Vec<Card>, NastranError> {
    let mut cards: Vec<Card> = Vec::new();
    for line in lines {
        let (head, data, format) = fields_of(&line.text);
        let continuation = head.is_empty() || head.starts_with('+') || head.starts_with('*');
        if continuation {
            let Some(card) = cards.last_mut() else {
                return Err(NastranError::at(
                    &line.source,
                    "bulk data",
                    format!(
                        "a continuation line ('{}') before any card",
                        line.text.trim()
                    ),
                ));
            };
            let block = if format == Format::Large || head.starts_with('*') {
                4
            } else {
                8
            };
            // a small- or free-field continuation starts a new line of 8 fields
            let n = card.fields.len();
            card.fields.resize(n.div_ceil(block) * block, String::new());
            card.fields.extend(data);
            continue;
        }
        let name = head.trim_end_matches('*').to_string();
        if !name.chars().next().is_some_and(|c| c.is_ascii_alphabetic()) {
            return Err(NastranError::at(
                &line.source,
                &name,
                format!(
                    "is not a card name (a bulk data line starts with a card name, '+' or '*'): '{}'",
                    line.text.trim()
                ),
            ));
        }
        cards.push(Card {
            name,
            fields: data,
            source: line.source,
        });
    }
    for card in &mut cards {
        while card.fields.last().is_some_and(|f| f.is_empty()) {
            card.fields.pop();
        }
    }
    Ok(cards)
}

/// The Nastran column name of data field `p` (1-based across continuation lines).
pub fn field_label(p: usize) -> String {
    let line = (p - 1) / 8;
    let field = (p - 1) % 8 + 2;
    if line == 0 {
        format!("field {field}")
    } else {
        format!("field {field} of continuation {line}")
    }
}

impl Card {
    /// The raw text of data field `p` (empty beyond the card's end).
    pub fn raw(&self, p: usize) -> &str {
        self.fields.get(p - 1).map_or("", |s| s.as_str())
    }

    /// The value of data field `p`.
    pub fn value(&self, p: usize) -> Value<'_> {
        classify(self.raw(p))
    }

    /// The card's id (its first field) for messages, if it is an integer.
    pub fn id(&self) -> Option<i64> {
        match self.value(1) {
            Value::Int(i) => Some(i),
            _ => None,
        }
    }

    /// An error about field `p` named `what` (the Quick Reference Guide's name for it).
    pub fn field_error(&self, p: usize, what: &str, reason: impl Into<String>) -> NastranError {
        NastranError::card(
            self,
            format!("{} ({what}): {}", field_label(p), reason.into()),
        )
    }

    /// An integer field that must be given.
    pub fn int(&self, p: usize, what: &str) -> Result<i64, NastranError> {
        match self.value(p) {
            Value::Int(i) => Ok(i),
            Value::Blank => Err(self.field_error(p, what, "missing: an integer is required")),
            _ => Err(self.field_error(
                p,
                what,
                format!("expected an integer, got '{}'", self.raw(p)),
            )),
        }
    }

    /// An integer field with a default when blank.
    pub fn int_or(&self, p: usize, what: &str, default: i64) -> Result<i64, NastranError> {
        match self.value(p) {
            Value::Blank => Ok(default),
            _ => self.int(p, what),
        }
    }

    /// An optional integer field (blank: None).
    pub fn int_opt(&self, p: usize, what: &str) -> Result<Option<i64>, NastranError> {
        match self.value(p) {
            Value::Blank => Ok(None),
            _ => self.int(p, what).map(Some),
        }
    }

    /// A positive id field (what every id field of Nastran is).
    pub fn id_field(&self, p: usize, what: &str) -> Result<u32, NastranError> {
        let i = self.int(p, what)?;
        u32::try_from(i)
            .ok()
            .filter(|&i| i > 0)
            .ok_or_else(|| self.field_error(p, what, format!("must be a positive id (got {i})")))
    }

    /// An optional positive id field (blank or 0: None).
    pub fn id_opt(&self, p: usize, what: &str) -> Result<Option<u32>, NastranError> {
        match self.int_opt(p, what)? {
            None | Some(0) => Ok(None),
            Some(_) => self.id_field(p, what).map(Some),
        }
    }

    /// A real field that must be given (an integer is accepted as its value).
    pub fn real(&self, p: usize, what: &str) -> Result<f64, NastranError> {
        match self.value(p) {
            Value::Real(r) => Ok(r),
            Value::Int(i) => Ok(i as f64),
            Value::Blank => Err(self.field_error(p, what, "missing: a real number is required")),
            Value::Text(t) => {
                Err(self.field_error(p, what, format!("expected a real number, got '{t}'")))
            }
        }
    }

    /// A real field with a default when blank.
    pub fn real_or(&self, p: usize, what: &str, default: f64) -> Result<f64, NastranError> {
        match self.value(p) {
            Value::Blank => Ok(default),
            _ => self.real(p, what),
        }
    }

    /// An optional real field.
    pub fn real_opt(&self, p: usize, what: &str) -> Result<Option<f64>, NastranError> {
        match self.value(p) {
            Value::Blank => Ok(None),
            _ => self.real(p, what).map(Some),
        }
    }

    /// A text field (blank: empty).
    pub fn text(&self, p: usize) -> &str {
        self.raw(p)
    }

    /// Nastran component digits (`123456`, `0`, blank = none): the components 1–6 named.
    pub fn components(&self, p: usize, what: &str) -> Result<Vec<u8>, NastranError> {
        let raw = self.raw(p);
        let mut out = Vec::new();
        for c in raw.chars() {
            match c.to_digit(10) {
                Some(0) if raw.len() == 1 => return Ok(out),
                Some(d @ 1..=6) if !out.contains(&(d as u8)) => out.push(d as u8),
                _ => {
                    return Err(self.field_error(
                        p,
                        what,
                        format!("expected component digits 1–6, each once (got '{raw}')"),
                    ))
                }
            }
        }
        out.sort_unstable();
        Ok(out)
    }

    /// The number of data fields the card holds (trailing blanks dropped).
    pub fn len(&self) -> usize {
        self.fields.len()
    }

    /// Whether the card holds no data field.
    pub fn is_empty(&self) -> bool {
        self.fields.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn deck(text: &str) -> Deck {
        Deck::from_text(Path::new("test.bdf"), text).unwrap()
    }

    /// The same GRID and CAERO1 written in small, large and free field, with explicit, implicit
    /// and free-field continuations, tabs and comments, read to the same fields.
    #[test]
    fn small_large_and_free_fields_agree() {
        let small = deck(
            "BEGIN BULK\n\
             GRID    12      0       1.0     -2.5    3.+2    0       246\n\
             CAERO1  101     1       1       6       4                       1       +CA101\n\
             +CA101  -1.     -.26795 0.0     2.0706  -1.     5.45205 0.0     2.0706\n\
             ENDDATA\n",
        );
        let large = deck(
            "BEGIN BULK\n\
             GRID*   12              0               1.0             -2.5            *G1\n\
             *G1     3.+2            0               246\n\
             CAERO1* 101             1               1               6\n\
             *       4                                               1\n\
             *       -1.             -.26795         0.0             2.0706\n\
             *       -1.             5.45205         0.0             2.0706\n",
        );
        let free = deck(
            "$ a comment line\n\
             GRID,12,0,1.0,-2.5,3.+2,0,246 $ trailing comment\n\
             CAERO1,101,1,1,6,4,,,1,+CA\n\
             +CA,-1.,-.26795,0.0,2.0706,-1.,5.45205,0.0,2.0706\n",
        );
        let tabs = deck("BEGIN BULK\nGRID\t12\t0\t1.0\t-2.5\t3.+2\t0\t246\nCAERO1\t101\t1\t1\t6\t4\t\t\t1\n\t-1.\t-.26795\t0.0\t2.0706\t-1.\t5.45205\t0.0\t2.0706\n");
        for d in [&small, &large, &free, &tabs] {
            assert_eq!(d.bulk.len(), 2);
            let g = &d.bulk[0];
            assert_eq!(g.name, "GRID");
            assert_eq!(g.int(1, "ID").unwrap(), 12);
            assert_eq!(g.real(5, "X3").unwrap(), 300.0);
            assert_eq!(g.components(7, "PS").unwrap(), vec![2, 4, 6]);
            let c = &d.bulk[1];
            assert_eq!(c.name, "CAERO1");
            assert_eq!(c.int(8, "IGID").unwrap(), 1);
            assert_eq!(c.real(10, "Y1").unwrap(), -0.26795);
            assert_eq!(c.real(16, "X43").unwrap(), 2.0706);
            assert_eq!(c.len(), 16);
        }
        assert_eq!(small.bulk[1].source.line, 3);
        assert!(!free.has_begin_bulk);
    }

    /// Sections: the executive up to CEND, case control up to BEGIN BULK, nothing after ENDDATA.
    #[test]
    fn sections_split() {
        let d = deck("SOL 145\nCEND\nSPC = 1\nBEGIN BULK\nSPC1,1,123,5\nENDDATA\nGRID,9\n");
        assert_eq!(d.executive.len(), 1);
        assert_eq!(d.case_control[0].text, "SPC = 1");
        assert_eq!(d.bulk.len(), 1);
    }

    /// INCLUDE relative to the including file, a quoted name over two lines, and a circle.
    #[test]
    fn includes_are_followed() {
        let dir = std::env::temp_dir().join(format!("gustkit-nastran-inc-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        std::fs::write(
            dir.join("sub/grids.inc"),
            "GRID,1,,0.,0.,0.\nINCLUDE 'more.inc'\n",
        )
        .unwrap();
        std::fs::write(dir.join("sub/more.inc"), "GRID,2,,1.,0.,0.\n").unwrap();
        std::fs::write(
            dir.join("main.bdf"),
            "SOL 103\nCEND\nBEGIN BULK\nINCLUDE 'sub/\ngrids.inc'\nGRID,3,,2.,0.,0.\nENDDATA\n",
        )
        .unwrap();
        let d = Deck::read(&dir.join("main.bdf")).unwrap();
        let ids: Vec<i64> = d.bulk.iter().map(|c| c.int(1, "ID").unwrap()).collect();
        assert_eq!(ids, vec![1, 2, 3]);
        assert!(d.bulk[1].source.file.ends_with("sub/more.inc"));
        std::fs::write(dir.join("sub/more.inc"), "INCLUDE 'grids.inc'\n").unwrap();
        let e = Deck::read(&dir.join("main.bdf")).unwrap_err().to_string();
        assert!(e.contains("includes itself"), "{e}");
        let e = Deck::from_text(Path::new("x.bdf"), "INCLUDE 'nowhere.bdf'\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("x.bdf line 1") && e.contains("nowhere.bdf"),
            "{e}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Field errors name the file, line, card, id, field and what was found.
    #[test]
    fn field_errors_name_their_place() {
        let d = deck("BEGIN BULK\nCQUAD4,7,1.5,1,2,3,4\n");
        let e = d.bulk[0].int(2, "PID").unwrap_err().to_string();
        assert!(
            e.contains("test.bdf line 2")
                && e.contains("CQUAD4 7")
                && e.contains("field 3 (PID)")
                && e.contains("'1.5'"),
            "{e}"
        );
        let e = Deck::from_text(Path::new("t.bdf"), "+C,1,2\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("before any card"), "{e}");
    }
}
