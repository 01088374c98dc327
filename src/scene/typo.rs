//! Parse errors in words a scene's author can act on: an unknown field or variant is named with
//! the names it could have meant, and the slips of someone who writes JSON or the command line's
//! fractions (a quoted name, brackets for a pair, `1/60`) are named with what RON wants instead.
//!
//! Every struct of the format denies unknown fields (`#[serde(deny_unknown_fields)]`), because
//! a misspelled optional field that is silently ignored runs a different scene from the one
//! written: `(pos: (0.5, 0.5), masss: 5.0)` would weigh 1 kg. RON reports such a field with the
//! list of the names it expected; this module picks the near ones out of that list.

use crate::readable::NotWhole;

/// The message for a RON error at `line`:`col` (1-based) of `text`: ron's own words, except for
/// an unknown field or variant, which is named with its place in the scene, the near names, and
/// every name allowed there; a missing field, named with its place; and the slips of
/// [`slip`].
pub(crate) fn message(code: &ron::Error, text: &str, line: usize, col: usize) -> String {
    let (before, after) = around(text, line, col);
    // ron's own words there ("Unexpected char '6'") would mislead: the hint replaces them.
    if let Some(hint) = slip(code, before, after.trim_start()) {
        return hint;
    }
    match code {
        ron::Error::NoSuchStructField {
            expected,
            found,
            outer,
        } => unknown("field", found, expected, outer.as_deref()),
        ron::Error::NoSuchEnumVariant {
            expected,
            found,
            outer,
        } => unknown("variant", found, expected, outer.as_deref()),
        ron::Error::MissingStructField { field, outer } => {
            let place = outer.as_deref().map(place).unwrap_or_default();
            format!("missing field `{field}`{place} (every field: docs/scene-format.md)")
        }
        other => other.to_string(),
    }
}

/// The line of the error split at it: what comes before, what from it on.
fn around(text: &str, line: usize, col: usize) -> (&str, &str) {
    let row = text.lines().nth(line.saturating_sub(1)).unwrap_or("");
    let at = row
        .char_indices()
        .nth(col.saturating_sub(1))
        .map_or(row.len(), |(i, _)| i);
    row.split_at(at)
}

/// What a newcomer to RON writes out of habit, and what RON wants instead (`after` starts at
/// the error's first character that is not a space):
/// - a quoted name where a name is wanted (`integrator: "Xpbd"`, as in JSON);
/// - a fraction (`dt: 1/60`, which the command line takes): RON reads `/` as a comment;
/// - brackets for a pair or a struct (`gravity: [0.0, -9.8]`), parentheses for a list;
/// - the command line's hyphens (`integrator: projective-dynamics`, `spring-damping: 2.0`),
///   for which ron suggests a raw identifier, `r#projective-dynamics`, that no scene knows;
/// - a comma left out between two fields or entries (ron says "Expected comma" and no more);
/// - a decimal, an exponent, a sign or a non-number where a whole number is wanted (`segments:
///   2.5`, `cols: 1e3`, `b: -1`), which ron reports as a missing comma before `.5` or a bad
///   digit, with no field named ([`whole_number`]).
fn slip(code: &ron::Error, before: &str, after: &str) -> Option<String> {
    match code {
        ron::Error::InvalidIntegerDigit { .. }
        | ron::Error::IntegerOutOfBounds
        | ron::Error::ExpectedInteger => whole_number(before, after),
        // `2.5` in a whole number's place: ron reads `2` and wants a comma before `.5`.
        ron::Error::ExpectedComma
            if before.ends_with(|c: char| c.is_ascii_digit())
                && after.starts_with('.')
                && after[1..].starts_with(|c: char| c.is_ascii_digit()) =>
        {
            whole_number(before, after)
        }
        ron::Error::SuggestRawIdentifier(name) if name.contains('-') => {
            let field = (after.strip_prefix(name.as_str()))
                .is_some_and(|rest| rest.trim_start().starts_with(':'));
            Some(if field {
                let snake = name.replace('-', "_");
                format!("a field's name has no hyphens: `{snake}`, not `{name}`")
            } else {
                let camel: String = name.split('-').map(capitalised).collect();
                let integrators = crate::solver::Integrator::ALL;
                let cli = if integrators.iter().any(|m| m.cli_name() == name) {
                    " (the command line's spelling)"
                } else {
                    ""
                };
                format!("a name has no hyphens: `{camel}`, not `{name}`{cli}")
            })
        }
        ron::Error::ExpectedIdentifier => {
            let quoted = after.strip_prefix('"')?;
            let name = &quoted[..quoted.find('"')?];
            Some(format!(
                "a name is written without quotes: `{name}`, not `\"{name}\"`"
            ))
        }
        ron::Error::UnexpectedChar(_) => {
            // ron stops at the `/` (a comment's start) or just past it.
            let (head, tail) = match before.trim_end().strip_suffix('/') {
                Some(head) => (head.trim_end(), after),
                None => (before.trim_end(), after.strip_prefix('/')?.trim_start()),
            };
            let number =
                |c: char| c.is_ascii_digit() || matches!(c, '.' | 'e' | 'E' | '_' | '-' | '+');
            let p = &head[head.trim_end_matches(number).len()..];
            let q = &tail[..tail.len() - tail.trim_start_matches(number).len()];
            let value = p.parse::<f64>().ok()? / q.parse::<f64>().ok()?;
            value.is_finite().then(|| {
                format!(
                    "RON has no fractions: write {p}/{q} as {value:?} (the command line's \
                     --dt and --time take fractions)"
                )
            })
        }
        ron::Error::ExpectedStructLike | ron::Error::ExpectedNamedStructLike(_) => {
            let inside = after.strip_prefix('[')?;
            let inside = &inside[..inside.find(']')?];
            Some(format!(
                "a pair or a struct is written in parentheses: ({inside}), not [{inside}]"
            ))
        }
        ron::Error::ExpectedArray => after
            .starts_with('(')
            .then(|| "a list is written in brackets: [ … ], not ( … )".to_string()),
        ron::Error::ExpectedComma => {
            // What follows, as far as its first name or number: a field (`integrator`), an
            // entry (`(pos`), a value (`0.2`).
            let stop = |c: char| c.is_whitespace() || matches!(c, ':' | ',' | ')' | ']');
            let next = &after[..after.find(stop).unwrap_or(after.len())];
            Some(if next.is_empty() {
                "a comma is missing here: RON separates fields and entries with commas".into()
            } else {
                format!(
                    "a comma is missing before `{next}`: RON separates fields and entries with \
                     commas"
                )
            })
        }
        _ => None,
    }
}

/// The message for a value that is not a whole number where one is wanted: the field's name
/// and the value as written, split by the error's place into `before` and `after`; `None` when
/// no field's name stands before the value (ron's own words then).
fn whole_number(before: &str, after: &str) -> Option<String> {
    let separator = |c: char| c.is_whitespace() || matches!(c, ':' | ',' | '(' | ')' | '[' | ']');
    let head = before.trim_end_matches(|c: char| !separator(c));
    let value = format!(
        "{}{}",
        &before[head.len()..],
        &after[..after.find(separator).unwrap_or(after.len())]
    );
    let head = head.trim_end().strip_suffix(':')?.trim_end();
    let field = &head[head
        .trim_end_matches(|c: char| c.is_alphanumeric() || c == '_')
        .len()..];
    if field.is_empty() || value.is_empty() {
        return None;
    }
    let how = match NotWhole::of(&value) {
        NotWhole::Negative => " of 0 or more",
        NotWhole::Fraction => ", written without a decimal point or an exponent",
        NotWhole::TooLarge => " no larger than its field holds",
        NotWhole::NotANumber => "",
    };
    Some(format!(
        "`{field}` takes a whole number{how}, not `{value}`"
    ))
}

/// `word` with its first letter in capitals: `projective` → `Projective`.
fn capitalised(word: &str) -> String {
    let mut chars = word.chars();
    chars.next().map_or_else(String::new, |first| {
        first.to_uppercase().chain(chars).collect()
    })
}

fn unknown(kind: &str, found: &str, expected: &[&str], outer: Option<&str>) -> String {
    let place = outer.map(place).unwrap_or_default();
    let mut text = format!("unknown {kind} `{found}`{place}");
    let near = near_names(found, expected);
    if !near.is_empty() {
        let listed: Vec<String> = near.iter().map(|n| format!("`{n}`")).collect();
        text += &format!("; did you mean {}?", listed.join(" or "));
    }
    if !expected.is_empty() {
        text += &format!(" (expected one of: {})", expected.join(", "));
    }
    text
}

/// Where in the scene a struct or enum of the format sits, in the file's own words.
fn place(outer: &str) -> String {
    let name = match outer {
        "Scene" => "the scene",
        "ParticleDef" => "a particle",
        "SpringDef" => "a spring",
        "ClickRules" => "`click`",
        "Iterations" => "`iterations`",
        "Generator" => "`generate`",
        "Integrator" => "`integrator`",
        "Pin" => "`pin`",
        "ObstacleDef" => "`obstacles`",
        "ContactSettings" => "`contact`",
        "BodyDef" => "a body of `bodies`",
        // The variants of the format's enums, named by the list they stand in.
        "Grid" | "Chain" => return format!(" in a `{outer}` of `generate`"),
        "Circle" | "Box" | "Segment" | "Polygon" => {
            return format!(" in a `{outer}` of `obstacles` or a body's `shape`");
        }
        other => return format!(" in `{other}`"),
    };
    format!(" in {name}")
}

/// The names within a small edit distance of `found`, nearest first: one edit for names of up
/// to four letters, two for longer ones (a swap of neighbours counts as one edit, as in `taer`).
pub(crate) fn near_names<'a>(found: &str, names: &[&'a str]) -> Vec<&'a str> {
    let limit = if found.chars().count() <= 4 { 1 } else { 2 };
    let found = found.to_lowercase();
    let mut near: Vec<(usize, &str)> = names
        .iter()
        .map(|&name| (edit_distance(&found, &name.to_lowercase()), name))
        .filter(|&(d, _)| d <= limit)
        .collect();
    near.sort_by_key(|&(d, _)| d);
    near.into_iter().map(|(_, name)| name).collect()
}

/// The optimal string alignment distance: insertions, deletions, substitutions and swaps of
/// two neighbouring characters, each one edit.
fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    let mut d = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for (i, row) in d.iter_mut().enumerate() {
        row[0] = i;
    }
    for (j, cell) in d[0].iter_mut().enumerate() {
        *cell = j;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut best = (d[i - 1][j] + 1)
                .min(d[i][j - 1] + 1)
                .min(d[i - 1][j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                best = best.min(d[i - 2][j - 2] + 1);
            }
            d[i][j] = best;
        }
    }
    d[a.len()][b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_names_catch_the_usual_typos() {
        let particle = ["pos", "vel", "mass", "pinned"];
        assert_eq!(near_names("masss", &particle), ["mass"]);
        assert_eq!(near_names("pined", &particle), ["pinned"]);
        assert_eq!(near_names("Pos", &particle), ["pos"]);
        assert_eq!(near_names("taer", &["tear", "dt", "ground"]), ["tear"]);
        assert_eq!(near_names("colour", &particle), Vec::<&str>::new());
    }

    #[test]
    fn distance_counts_a_swap_as_one_edit() {
        assert_eq!(edit_distance("taer", "tear"), 1);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("stifness", "stiffness"), 1);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
    }
}
