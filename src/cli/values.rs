//! Parsers of the command line's comma-separated numbers (`--eye x,y,z`, `--cell x0,y0,x1,y1`, `--spacing dx,dy`,
//! height bands, lines of an eyes file), written once so that every flag says the same about a bad value.

/// Parses `N` finite numbers separated by commas (spaces around them allowed); `form` names them for the message
/// (`x,y,z`).
pub fn numbers<const N: usize>(s: &str, form: &str) -> Result<[f64; N], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != N {
        return Err(format!(
            "expected {form} ({N} comma-separated numbers), got {}",
            excerpt(s)
        ));
    }
    let mut v = [0.0; N];
    for (x, text) in v.iter_mut().zip(&parts) {
        *x = match text.parse::<f64>() {
            Ok(x) if x.is_finite() => x,
            _ => return Err(format!("{} is not a finite number", excerpt(text))),
        };
    }
    Ok(v)
}

/// `s` quoted for a message, cut after 60 characters (a line of an eyes file may be megabytes long).
fn excerpt(s: &str) -> String {
    const KEEP: usize = 60;
    match s.char_indices().nth(KEEP) {
        None => format!("{s:?}"),
        Some((cut, _)) => format!("{:?}… ({} characters)", &s[..cut], s.chars().count()),
    }
}

/// Parses `x,y,z`.
pub fn parse_point(s: &str) -> Result<[f64; 3], String> {
    numbers(s, "x,y,z")
}

/// Parses `x0,y0,x1,y1`.
pub fn parse_rect(s: &str) -> Result<[f64; 4], String> {
    numbers(s, "x0,y0,x1,y1")
}

/// Parses `a,b`.
pub fn parse_pair(s: &str) -> Result<[f64; 2], String> {
    numbers(s, "two values a,b")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_value_is_cut_in_the_message() {
        let long = "7".repeat(10_000);
        let e = parse_point(&long).expect_err("one number");
        assert!(e.len() < 150, "{e}");
        assert!(e.contains("… (10000 characters)"), "{e}");
        let e = parse_point(&format!("1,2,{long}x")).expect_err("not a number");
        assert!(
            e.len() < 150 && e.contains("… (10001 characters) is not a finite number"),
            "{e}"
        );
        assert_eq!(
            parse_point("1,2").expect_err("two numbers"),
            "expected x,y,z (3 comma-separated numbers), got \"1,2\""
        );
    }

    #[test]
    fn numbers_name_what_is_wrong() {
        assert_eq!(parse_point(" 1, -2.5 ,3e2"), Ok([1.0, -2.5, 300.0]));
        assert_eq!(
            parse_point("1,2"),
            Err("expected x,y,z (3 comma-separated numbers), got \"1,2\"".into())
        );
        assert_eq!(
            numbers::<2>("10,10,10", "dx,dy"),
            Err("expected dx,dy (2 comma-separated numbers), got \"10,10,10\"".into())
        );
        assert_eq!(parse_rect("0,0,1,nan"), Err("\"nan\" is not a finite number".into()));
        assert_eq!(parse_pair("a,1"), Err("\"a\" is not a finite number".into()));
        assert_eq!(parse_pair("inf,1"), Err("\"inf\" is not a finite number".into()));
    }
}
