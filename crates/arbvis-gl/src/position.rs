//! Turning a driver's compile message into a line and column of the program text.
//!
//! Drivers differ: Mesa's ARB assembler says `line 3, char 1: error: ...`, NVIDIA's
//! `line 3, column 1:  error: ...`, Mesa's GLSL compiler `0:3(5): error: ...`, NVIDIA's
//! `0(3) : error C0000: ...` (no column: where the message quotes a name found on that
//! line, the name's column is taken, [`with_quoted_column`]). The ARB
//! `GL_PROGRAM_ERROR_POSITION_ARB` is a byte offset by the spec, but Mesa's is not, so the
//! message wins when it names a position and the byte offset is the fallback.

/// A 1-based line and optional column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Position {
    /// 1-based line.
    pub line: u32,
    /// 1-based column, when known.
    pub column: Option<u32>,
}

/// Parse a position out of a driver message; `None` when the message names none.
pub fn from_message(message: &str) -> Option<Position> {
    arb_style(message)
        .or_else(|| mesa_glsl_style(message))
        .or_else(|| nvidia_style(message))
}

/// Position of a byte offset in `text` (1-based line and column).
pub fn from_byte_offset(text: &str, offset: usize) -> Position {
    let offset = offset.min(text.len());
    let before = &text.as_bytes()[..offset];
    let line = before.iter().filter(|&&b| b == b'\n').count() as u32 + 1;
    let line_start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |p| p + 1);
    Position {
        line,
        column: Some((offset - line_start) as u32 + 1),
    }
}

/// The text of 1-based `line` of `text` (empty when out of range).
pub fn source_line(text: &str, line: u32) -> String {
    text.lines()
        .nth(line.saturating_sub(1) as usize)
        .unwrap_or("")
        .trim_end()
        .to_string()
}

fn leading_number(s: &str) -> Option<(u32, &str)> {
    let end = s.find(|c: char| !c.is_ascii_digit()).unwrap_or(s.len());
    if end == 0 {
        return None;
    }
    Some((s[..end].parse().ok()?, &s[end..]))
}

/// `line 3, char 1: ...` (Mesa ARB assembler), `line 3, column 1: ...` (NVIDIA's).
fn arb_style(message: &str) -> Option<Position> {
    let rest = &message[message.find("line ")? + 5..];
    let (line, rest) = leading_number(rest)?;
    let column = rest
        .strip_prefix(", char ")
        .or_else(|| rest.strip_prefix(", column "))
        .and_then(leading_number)
        .map(|(c, _)| c);
    Some(Position { line, column })
}

/// `pos` with a column where it has none and `message` quotes a name (`"name"` or
/// `'name'`) that appears on its line of `text`: the name's first column there.
pub fn with_quoted_column(pos: Position, message: &str, text: &str) -> Position {
    if pos.column.is_some() {
        return pos;
    }
    let line = source_line(text, pos.line);
    let column = ['"', '\'']
        .iter()
        .flat_map(|&q| message.split(q).skip(1).step_by(2))
        .filter(|name| !name.is_empty() && !name.contains(char::is_whitespace))
        .find_map(|name| line.find(name))
        .map(|at| line[..at].chars().count() as u32 + 1);
    Position { column, ..pos }
}

/// `0:3(5): error: ...` (Mesa GLSL).
fn mesa_glsl_style(message: &str) -> Option<Position> {
    for (i, _) in message.match_indices(':') {
        let head = &message[..i];
        let src_start = head
            .rfind(|c: char| !c.is_ascii_digit())
            .map_or(0, |p| p + 1);
        if src_start == head.len() {
            continue;
        }
        let Some((line, rest)) = leading_number(&message[i + 1..]) else {
            continue;
        };
        if let Some((column, rest)) = rest.strip_prefix('(').and_then(leading_number) {
            if rest.starts_with(')') {
                return Some(Position {
                    line,
                    column: Some(column),
                });
            }
        }
    }
    None
}

/// `0(3) : error C0000: ...` (NVIDIA GLSL).
fn nvidia_style(message: &str) -> Option<Position> {
    for (i, _) in message.match_indices('(') {
        let head = &message[..i];
        if head.is_empty() || !head.ends_with(|c: char| c.is_ascii_digit()) {
            continue;
        }
        if let Some((line, rest)) = leading_number(&message[i + 1..]) {
            if rest.starts_with(')') {
                return Some(Position { line, column: None });
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_mesa_arb_message() {
        let p =
            from_message("line 3, char 14: error: syntax error, unexpected $undefined").unwrap();
        assert_eq!(
            p,
            Position {
                line: 3,
                column: Some(14)
            }
        );
    }

    #[test]
    fn parses_mesa_glsl_message() {
        let p = from_message("0:7(12): error: `foo' undeclared").unwrap();
        assert_eq!(
            p,
            Position {
                line: 7,
                column: Some(12)
            }
        );
    }

    #[test]
    fn parses_nvidia_glsl_message() {
        let p = from_message("0(9) : error C1008: undefined variable \"foo\"").unwrap();
        assert_eq!(
            p,
            Position {
                line: 9,
                column: None
            }
        );
    }

    #[test]
    fn parses_nvidia_arb_message() {
        assert_eq!(
            from_message("line 4, column 1:  error: invalid statement"),
            Some(Position {
                line: 4,
                column: Some(1)
            })
        );
    }

    #[test]
    fn a_quoted_name_on_the_line_gives_the_column() {
        let text = "void main() {\n    frag_color = v * undeclared_gain;\n}\n";
        let pos =
            from_message("0(2) : error C1503: undefined variable \"undeclared_gain\"").unwrap();
        assert_eq!(pos.column, None);
        let with = with_quoted_column(
            pos,
            "0(2) : error C1503: undefined variable \"undeclared_gain\"",
            text,
        );
        assert_eq!(
            with,
            Position {
                line: 2,
                column: Some(22)
            }
        );
        // A quoted name not on the line, or a column already known: unchanged.
        assert_eq!(with_quoted_column(pos, "error: \"elsewhere\"", text), pos);
        let known = Position {
            line: 2,
            column: Some(3),
        };
        assert_eq!(with_quoted_column(known, "\"v\"", text), known);
    }

    #[test]
    fn no_position_in_plain_message() {
        assert_eq!(from_message("out of memory"), None);
    }

    #[test]
    fn byte_offset_to_line_and_column() {
        let text = "!!ARBfp1.0\nTEMP a;\nMOV b, a;\n";
        assert_eq!(
            from_byte_offset(text, 0),
            Position {
                line: 1,
                column: Some(1)
            }
        );
        assert_eq!(
            from_byte_offset(text, 15),
            Position {
                line: 2,
                column: Some(5)
            }
        );
        assert_eq!(from_byte_offset(text, 10_000).line, 4);
        assert_eq!(source_line(text, 3), "MOV b, a;");
    }
}
