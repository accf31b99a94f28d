//! The executive control section (which solution) and the case control section (which bulk data
//! sets each subcase selects, which sets of grids, which outputs), read for what gustkit uses;
//! every other statement is named in one warning line per section, never silently dropped.

use super::deck::Statement;
use super::NastranError;
use std::collections::BTreeMap;

/// The analysis an input asks for, from MSC's SOL numbers (or names) or NASTRAN-95's rigid
/// formats (`APP AERO` with `SOL 10` or `11`, `APP DISP` with `SOL 3`).
#[derive(Clone, Debug, PartialEq)]
pub enum Solution {
    /// Normal modes (SOL 103, SEMODES; NASTRAN-95 APP DISP SOL 3).
    Modes,
    /// Aeroelastic flutter (SOL 145, SEFLUTTR; NASTRAN-95 APP AERO SOL 10).
    Flutter,
    /// Dynamic aeroelastic response: frequency, random and transient gust response (SOL 146,
    /// SEAERO; NASTRAN-95 APP AERO SOL 11).
    AeroResponse,
    /// Anything else, as written.
    Other(String),
}

/// What the executive control section asks for.
#[derive(Clone, Debug, Default)]
pub struct Executive {
    /// The solution statement as written (`145`, `10,0`, `SEFLUTTR`), if any.
    pub sol: Option<String>,
    /// NASTRAN-95's approach (`AERO`, `DISP`), if any.
    pub app: Option<String>,
    /// One line naming the statements gustkit does not use, if there are any.
    pub warnings: Vec<String>,
}

impl Executive {
    /// Reads the executive statements.
    pub fn parse(statements: &[Statement]) -> Result<Self, NastranError> {
        let mut out = Executive::default();
        let mut unused: Vec<String> = Vec::new();
        let mut in_alter = 0usize;
        let mut alter_active = false;
        for s in statements {
            let text = s.text.trim();
            let (word, rest) = split_word(text);
            if alter_active {
                if matches!(word.as_str(), "ENDALTER" | "ENDDMAP") {
                    alter_active = false;
                } else {
                    in_alter += 1;
                }
                continue;
            }
            match word.as_str() {
                "SOL" => {
                    let v = rest.trim().trim_end_matches('$').trim();
                    if v.is_empty() {
                        return Err(NastranError::at(
                            &s.source,
                            "SOL",
                            "names no solution (write SOL 145, SOL 146 or SOL 103)".into(),
                        ));
                    }
                    out.sol = Some(v.to_ascii_uppercase());
                }
                "APP" => out.app = Some(rest.trim().to_ascii_uppercase()),
                "ALTER" | "COMPILE" | "MALTER" => {
                    alter_active = true;
                    push_once(&mut unused, &word);
                }
                _ => push_once(&mut unused, &word),
            }
        }
        if !unused.is_empty() {
            let mut line = format!(
                "executive control: not used by gustkit: {}",
                unused.join(", ")
            );
            if in_alter > 0 {
                line.push_str(&format!(" (DMAP alters, {in_alter} lines, not run)"));
            }
            out.warnings.push(line);
        }
        Ok(out)
    }

    /// The analysis asked for; None without a SOL statement.
    pub fn solution(&self) -> Option<Solution> {
        let sol = self.sol.as_deref()?;
        let number = sol.split([',', ' ']).next().unwrap_or("");
        let aero = self.app.as_deref().is_some_and(|a| a.starts_with("AERO"));
        Some(match (aero, number) {
            (true, "10") => Solution::Flutter,
            (true, "11") => Solution::AeroResponse,
            (false, "3") if self.app.is_some() => Solution::Modes,
            (false, "103" | "SEMODES") => Solution::Modes,
            (false, "145" | "SEFLUTTR") => Solution::Flutter,
            (false, "146" | "SEAERO") => Solution::AeroResponse,
            _ => Solution::Other(sol.to_string()),
        })
    }
}

/// A case control selection: a set id, ALL or NONE.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Selection {
    Id(u32),
    All,
    None,
}

/// An output request (`DISPLACEMENT(PSDF, RMS) = 5`): what, its options, which set.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputRequest {
    pub options: Vec<String>,
    pub selection: Selection,
}

/// What one subcase selects (the global part above the first SUBCASE fills what a subcase leaves
/// out: see [`CaseControl::subcase`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Subcase {
    pub id: u32,
    pub title: Option<String>,
    pub subtitle: Option<String>,
    pub label: Option<String>,
    /// Bulk data selections by their full name (`SPC`, `MPC`, `METHOD`, `CMETHOD`, `FMETHOD`,
    /// `SDAMPING`, `FREQUENCY`, `GUST`, `RANDOM`, `DLOAD`, `TSTEP`) → the set id.
    pub selections: BTreeMap<&'static str, u32>,
    /// Output requests by their full name (`DISPLACEMENT`, `ACCELERATION`, `SPCFORCES`,
    /// `MONITOR`, `SDISPLACEMENT`: the modal coordinates).
    pub outputs: BTreeMap<&'static str, OutputRequest>,
}

/// The bulk data selections gustkit reads: full name and the shortest form Nastran accepts.
const SELECTIONS: [(&str, &str); 11] = [
    ("SPC", "SPC"),
    ("MPC", "MPC"),
    ("METHOD", "METH"),
    ("CMETHOD", "CMET"),
    ("FMETHOD", "FMET"),
    ("SDAMPING", "SDAM"),
    ("FREQUENCY", "FREQ"),
    ("GUST", "GUST"),
    ("RANDOM", "RAND"),
    ("DLOAD", "DLOA"),
    ("TSTEP", "TSTE"),
];

/// The output requests gustkit writes: full name and accepted forms (by their first four
/// letters; VECTOR is Nastran's other name for DISPLACEMENT).
const OUTPUTS: [(&str, &[&str]); 5] = [
    ("DISPLACEMENT", &["DISP", "VECT"]),
    ("ACCELERATION", &["ACCE"]),
    ("SPCFORCES", &["SPCF"]),
    ("MONITOR", &["MONI"]),
    ("SDISPLACEMENT", &["SDIS"]),
];

/// Selections of direct matrix input, which change the model and which gustkit cannot read.
const MATRIX_INPUT: [&str; 7] = ["K2GG", "M2GG", "B2GG", "K2PP", "M2PP", "B2PP", "P2G"];

/// The case control section.
#[derive(Clone, Debug, Default)]
pub struct CaseControl {
    /// What stands above the first SUBCASE.
    pub global: Subcase,
    pub subcases: Vec<Subcase>,
    /// `SET n = …` lists of ids (THRU ranges expanded, EXCEPT applied); ALL as None.
    pub sets: BTreeMap<u32, Option<Vec<u32>>>,
    pub warnings: Vec<String>,
}

impl CaseControl {
    /// Reads the case control statements.
    pub fn parse(statements: &[Statement]) -> Result<Self, NastranError> {
        let mut out = CaseControl::default();
        let mut unused: Vec<String> = Vec::new();
        let mut not_written: Vec<String> = Vec::new();
        let mut plot_lines = 0usize;
        let mut in_plot = false;
        let mut current: Option<Subcase> = None;
        let mut i = 0;
        while i < statements.len() {
            let s = &statements[i];
            let mut text = s.text.trim().to_string();
            i += 1;
            let (word, rest) = split_word(&text);
            if in_plot {
                plot_lines += 1;
                continue;
            }
            if word == "OUTPUT" {
                let kind = rest
                    .trim()
                    .trim_start_matches('(')
                    .trim_end_matches(')')
                    .trim();
                if !kind.is_empty() {
                    in_plot = true;
                    push_once(&mut unused, &format!("OUTPUT({kind}) section"));
                }
                continue;
            }
            // a SET list runs on over lines that end in a comma
            if word == "SET" {
                while text.ends_with(',') && i < statements.len() {
                    text.push(' ');
                    text.push_str(statements[i].text.trim());
                    i += 1;
                }
                let (id, ids) =
                    parse_set(&text).map_err(|r| NastranError::at(&s.source, "SET", r))?;
                if out.sets.insert(id, ids).is_some() {
                    return Err(NastranError::at(
                        &s.source,
                        &format!("SET {id}"),
                        "is defined twice".into(),
                    ));
                }
                continue;
            }
            if word == "SUBCASE" || word == "SUBC" {
                let id = rest
                    .trim()
                    .parse::<u32>()
                    .ok()
                    .filter(|&n| n > 0)
                    .ok_or_else(|| {
                        NastranError::at(
                            &s.source,
                            "SUBCASE",
                            format!("needs a positive id (got '{}')", rest.trim()),
                        )
                    })?;
                if let Some(done) = current.take() {
                    out.subcases.push(done);
                }
                current = Some(Subcase {
                    id,
                    ..Default::default()
                });
                continue;
            }
            let target = current.as_mut().unwrap_or(&mut out.global);
            let (key, options, value) = split_assignment(&text);
            match key.as_str() {
                "TITLE" | "TITL" => target.title = Some(value.to_string()),
                "SUBTITLE" | "SUBT" => target.subtitle = Some(value.to_string()),
                "LABEL" | "LABE" => target.label = Some(value.to_string()),
                _ => {}
            }
            if matches!(
                key.as_str(),
                "TITLE" | "TITL" | "SUBTITLE" | "SUBT" | "LABEL" | "LABE"
            ) {
                continue;
            }
            let short = &key[..key.len().min(4)];
            if MATRIX_INPUT.contains(&key.as_str()) {
                return Err(NastranError::at(
                    &s.source,
                    &key,
                    "selects direct matrix input (DMIG), which gustkit does not read: give the structure as elements, masses and springs".into(),
                ));
            }
            if let Some((full, _)) = SELECTIONS
                .iter()
                .find(|(full, min)| short == *min && full.starts_with(key.as_str()))
            {
                let id = value
                    .split_whitespace()
                    .next()
                    .and_then(|v| v.parse::<u32>().ok())
                    .filter(|&n| n > 0)
                    .ok_or_else(|| {
                        NastranError::at(
                            &s.source,
                            full,
                            format!("needs a positive set id (got '{value}')"),
                        )
                    })?;
                target.selections.insert(full, id);
                continue;
            }
            if let Some((full, _)) = OUTPUTS.iter().find(|(_, forms)| forms.contains(&short)) {
                let selection = match value.trim() {
                    "ALL" => Selection::All,
                    "NONE" => Selection::None,
                    v => Selection::Id(v.parse::<u32>().ok().filter(|&n| n > 0).ok_or_else(
                        || {
                            NastranError::at(
                                &s.source,
                                full,
                                format!("needs ALL, NONE or a set id (got '{v}')"),
                            )
                        },
                    )?),
                };
                target
                    .outputs
                    .insert(full, OutputRequest { options, selection });
                continue;
            }
            if matches!(
                short,
                "VELO"
                    | "FORC"
                    | "ELFO"
                    | "STRE"
                    | "ELST"
                    | "STRA"
                    | "MPCF"
                    | "OLOA"
                    | "GPFO"
                    | "ESE"
                    | "EKE"
            ) {
                push_once(&mut not_written, &key);
            } else {
                push_once(&mut unused, &key);
            }
        }
        if let Some(done) = current.take() {
            out.subcases.push(done);
        }
        for sub in std::iter::once(&out.global).chain(&out.subcases) {
            for (name, req) in &sub.outputs {
                if let Selection::Id(id) = req.selection {
                    if !out.sets.contains_key(&id) {
                        return Err(NastranError {
                            place: "case control".into(),
                            what: name.to_string(),
                            reason: format!(
                                "selects SET {id}, which the case control does not define"
                            ),
                        });
                    }
                }
            }
        }
        if !unused.is_empty() {
            let mut line = format!("case control: not used by gustkit: {}", unused.join(", "));
            if plot_lines > 0 {
                line.push_str(&format!(
                    " ({plot_lines} plot lines; gustkit draws its own figures)"
                ));
            }
            out.warnings.push(line);
        }
        if !not_written.is_empty() {
            out.warnings.push(format!(
                "case control: output requests gustkit does not write: {} (it writes DISPLACEMENT, ACCELERATION, SPCFORCES, SDISPLACEMENT and MONITOR)",
                not_written.join(", ")
            ));
        }
        Ok(out)
    }

    /// The effective selections of subcase `id` (the global ones where it says nothing); the
    /// global case when the deck has no subcase and `id` is 1.
    pub fn subcase(&self, id: u32) -> Option<Subcase> {
        let sub = match self.subcases.iter().find(|s| s.id == id) {
            Some(s) => s,
            None if self.subcases.is_empty() && id == 1 => &self.global,
            None => return None,
        };
        let mut merged = self.global.clone();
        merged.id = id;
        merged.selections.extend(sub.selections.clone());
        merged.outputs.extend(sub.outputs.clone());
        for (mine, global) in [
            (&sub.title, &mut merged.title),
            (&sub.subtitle, &mut merged.subtitle),
            (&sub.label, &mut merged.label),
        ] {
            if mine.is_some() {
                *global = mine.clone();
            }
        }
        Some(merged)
    }

    /// The subcase ids (1 alone for a deck without SUBCASE).
    pub fn subcase_ids(&self) -> Vec<u32> {
        if self.subcases.is_empty() {
            vec![1]
        } else {
            self.subcases.iter().map(|s| s.id).collect()
        }
    }
}

/// The first word (upper case) and the rest of a statement.
fn split_word(text: &str) -> (String, &str) {
    let t = text.trim_start();
    let end = t
        .find(|c: char| c.is_whitespace() || c == '=' || c == '(' || c == ',')
        .unwrap_or(t.len());
    (t[..end].to_ascii_uppercase(), &t[end..])
}

/// `KEY(opt, opt) = value` → (KEY, options, value); a statement without `=` has its words after
/// the key as value.
fn split_assignment(text: &str) -> (String, Vec<String>, &str) {
    let (key, rest) = split_word(text);
    let rest = rest.trim_start();
    let (options, rest) = match rest.strip_prefix('(') {
        Some(r) => match r.find(')') {
            Some(j) => (
                r[..j]
                    .split(',')
                    .map(|o| o.trim().to_ascii_uppercase())
                    .filter(|o| !o.is_empty())
                    .collect(),
                &r[j + 1..],
            ),
            None => (Vec::new(), r),
        },
        None => (Vec::new(), rest),
    };
    let rest = rest.trim_start();
    let value = rest.strip_prefix('=').unwrap_or(rest).trim();
    (key, options, value)
}

/// `SET n = 1, 2, 9 THRU 12 EXCEPT 10, 1040` (or `= ALL`).
fn parse_set(text: &str) -> Result<(u32, Option<Vec<u32>>), String> {
    let (_, rest) = split_word(text);
    let (id, list) = rest
        .split_once('=')
        .ok_or_else(|| format!("expected SET n = list (got '{text}')"))?;
    let id: u32 = id
        .trim()
        .parse()
        .ok()
        .filter(|&n| n > 0)
        .ok_or_else(|| format!("needs a positive id (got '{}')", id.trim()))?;
    let tokens: Vec<String> = list
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .map(|t| t.to_ascii_uppercase())
        .collect();
    if tokens.len() == 1 && tokens[0] == "ALL" {
        return Ok((id, None));
    }
    let number = |t: &str| -> Result<u32, String> {
        t.parse::<u32>().map_err(|_| {
            format!(
                "SET {id}: expected ids, THRU and EXCEPT (got '{t}'; sets of reals are not read)"
            )
        })
    };
    let mut ids: Vec<u32> = Vec::new();
    let mut except = false;
    let mut range: Option<(u32, u32)> = None;
    let mut k = 0;
    while k < tokens.len() {
        let t = tokens[k].as_str();
        if t == "EXCEPT" {
            except = true;
            k += 1;
            continue;
        }
        let a = number(t)?;
        if except && range.is_some_and(|(lo, hi)| (lo..=hi).contains(&a)) {
            ids.retain(|&x| x != a);
            k += 1;
            continue;
        }
        except = false;
        if tokens.get(k + 1).map(|s| s.as_str()) == Some("THRU") {
            let b = number(tokens.get(k + 2).ok_or("THRU without its end")?)?;
            if b < a {
                return Err(format!("SET {id}: {a} THRU {b} runs backwards"));
            }
            ids.extend(a..=b);
            range = Some((a, b));
            k += 3;
        } else {
            ids.push(a);
            range = None;
            k += 1;
        }
    }
    ids.sort_unstable();
    ids.dedup();
    Ok((id, Some(ids)))
}

fn push_once(list: &mut Vec<String>, word: &str) {
    if !list.iter().any(|w| w == word) {
        list.push(word.to_string());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nastran::Deck;
    use std::path::Path;

    fn sections(text: &str) -> (Executive, CaseControl) {
        let d = Deck::from_text(Path::new("t.bdf"), text).unwrap();
        (
            Executive::parse(&d.executive).unwrap(),
            CaseControl::parse(&d.case_control).unwrap(),
        )
    }

    /// NASTRAN-95's rigid formats and MSC's SOL numbers name the same analyses; the statements
    /// gustkit does not use are named in one line.
    #[test]
    fn solutions_and_executive_warnings() {
        let (e, _) = sections("ID D10021A,NASTRAN\nAPP   AERO\nSOL   10,0\nTIME  10\nALTER 66 $\nMATGPR GPL $\nENDALTER $\nCEND\nBEGIN BULK\n");
        assert_eq!(e.solution(), Some(Solution::Flutter));
        assert_eq!(e.warnings.len(), 1);
        assert!(
            e.warnings[0].contains("ID, TIME, ALTER") && e.warnings[0].contains("1 lines"),
            "{:?}",
            e.warnings
        );
        let (e, _) = sections("SOL 146\nCEND\nBEGIN BULK\n");
        assert_eq!(e.solution(), Some(Solution::AeroResponse));
        assert!(e.warnings.is_empty());
        let (e, _) = sections("SOL SEFLUTTR\nCEND\n");
        assert_eq!(e.solution(), Some(Solution::Flutter));
    }

    /// Selections by full and short names, subcases inheriting the global part, SET lists with
    /// THRU, EXCEPT and continuation lines, output requests with options, and one warning line
    /// for what is not used.
    #[test]
    fn case_control_selections_sets_and_outputs() {
        let (_, c) = sections(
            "SOL 146\nCEND\nTITLE = JET TRANSPORT WING\nECHO = BOTH\nSPC = 14\nMETH = 10\nSDAMP = 2000\n\
             FREQ = 40\nRANDOM = 1031\nOUTPUT\nSET 1 = 1, 2 , 12\nSET 2 = 1 , 9 THRU 12,\n 1040\n\
             SET 3 = 1 THRU 10 EXCEPT 4 5 20\nDISP(PSDF, RMS) = 2\nACCE = ALL\nSTRESS = ALL\n\
             SUBCASE 1\nGUST = 3002\nLABEL = SYMMETRIC\nSUBCASE 2\nSPC = 15\n\
             OUTPUT(XYOUT)\nXTITLE = VELOCITY\nXYPLOT DISP /1(T3)\nBEGIN BULK\n",
        );
        assert_eq!(c.sets[&1], Some(vec![1, 2, 12]));
        assert_eq!(c.sets[&2], Some(vec![1, 9, 10, 11, 12, 1040]));
        assert_eq!(c.sets[&3], Some(vec![1, 2, 3, 6, 7, 8, 9, 10, 20]));
        let s1 = c.subcase(1).unwrap();
        assert_eq!(s1.selections["SPC"], 14);
        assert_eq!(s1.selections["METHOD"], 10);
        assert_eq!(s1.selections["SDAMPING"], 2000);
        assert_eq!(s1.selections["FREQUENCY"], 40);
        assert_eq!(s1.selections["GUST"], 3002);
        assert_eq!(s1.label.as_deref(), Some("SYMMETRIC"));
        assert_eq!(s1.title.as_deref(), Some("JET TRANSPORT WING"));
        assert_eq!(
            s1.outputs["DISPLACEMENT"],
            OutputRequest {
                options: vec!["PSDF".into(), "RMS".into()],
                selection: Selection::Id(2)
            }
        );
        assert_eq!(s1.outputs["ACCELERATION"].selection, Selection::All);
        let s2 = c.subcase(2).unwrap();
        assert_eq!(s2.selections["SPC"], 15);
        assert!(!s2.selections.contains_key("GUST"));
        assert_eq!(c.subcase_ids(), vec![1, 2]);
        assert_eq!(c.warnings.len(), 2, "{:?}", c.warnings);
        assert!(
            c.warnings[0].contains("ECHO")
                && c.warnings[0].contains("OUTPUT(XYOUT)")
                && c.warnings[0].contains("2 plot lines"),
            "{:?}",
            c.warnings
        );
        assert!(c.warnings[1].contains("STRESS"), "{:?}", c.warnings);
    }

    /// Case control errors name the statement and its line.
    #[test]
    fn case_control_errors() {
        for (text, needle) in [
            (
                "SOL 103\nCEND\nSPC = X\nBEGIN BULK\n",
                "SPC: needs a positive set id",
            ),
            ("SOL 103\nCEND\nDISP = 7\nBEGIN BULK\n", "SET 7"),
            ("SOL 103\nCEND\nM2GG = MX\nBEGIN BULK\n", "DMIG"),
            (
                "SOL 103\nCEND\nSET 4 = 3 THRU 1\nBEGIN BULK\n",
                "runs backwards",
            ),
            ("SOL 103\nCEND\nSUBCASE A\nBEGIN BULK\n", "positive id"),
        ] {
            let d = Deck::from_text(Path::new("t.bdf"), text).unwrap();
            let e = CaseControl::parse(&d.case_control).unwrap_err().to_string();
            assert!(e.contains(needle), "{text}: {e}");
        }
    }
}
