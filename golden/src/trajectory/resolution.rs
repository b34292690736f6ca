//! Image resolutions as the command line and trajectory specs write them: a name (`hd`, `fhd`,
//! `qhd`) or `WxH`. The one parser, with one set of bounds.

/// The largest width or height accepted.
pub const MAX_SIDE: u32 = 16384;

/// The named resolutions, `(name, width, height)`.
pub const NAMED: [(&str, u32, u32); 3] = [("hd", 1280, 720), ("fhd", 1920, 1080), ("qhd", 2560, 1440)];

/// Parses `hd` (1280x720), `fhd` (1920x1080), `qhd` (2560x1440) or `WxH` (either case, sides in
/// `1..=`[`MAX_SIDE`]) to `(width, height)`. The error names the value.
pub fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let l = s.trim().to_ascii_lowercase();
    if let Some(&(_, w, h)) = NAMED.iter().find(|(name, _, _)| *name == l) {
        return Ok((w, h));
    }
    let (w, h) =
        l.split_once('x').ok_or_else(|| format!("resolution '{s}': expected hd, fhd, qhd or WxH"))?;
    let side = |v: &str, what: &str| parse_side(v).map_err(|e| format!("resolution '{s}': {what} {e}"));
    Ok((side(w, "width")?, side(h, "height")?))
}

/// Parses one image side: an integer in `1..=`[`MAX_SIDE`]. The error names the value.
pub fn parse_side(v: &str) -> Result<u32, String> {
    match v.parse::<u32>() {
        Ok(n) if (1..=MAX_SIDE).contains(&n) => Ok(n),
        _ => Err(format!("'{v}' is not an integer from 1 to {MAX_SIDE}")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_sizes() {
        assert_eq!(parse_resolution("hd"), Ok((1280, 720)));
        assert_eq!(parse_resolution(" FHD "), Ok((1920, 1080)));
        assert_eq!(parse_resolution("qhd"), Ok((2560, 1440)));
        assert_eq!(parse_resolution("320x240"), Ok((320, 240)));
        assert_eq!(parse_resolution("64X32"), Ok((64, 32)));
        assert_eq!(parse_resolution("16384x1"), Ok((16384, 1)));
    }

    #[test]
    fn errors_name_the_value() {
        for bad in ["", "x", "0x5", "12x", "uhd", "16385x10", "10x-1"] {
            let e = parse_resolution(bad).unwrap_err();
            assert!(e.contains(&format!("'{bad}'")), "{bad}: {e}");
        }
        assert!(parse_resolution("0x5").unwrap_err().contains("width '0'"));
        assert!(parse_resolution("5x99999").unwrap_err().contains("height '99999'"));
    }
}
