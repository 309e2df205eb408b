//! Numbers as people read them: rounded values (full precision stays in the JSON outputs;
//! byte counts: [`volux_core::units::format_bytes`]).

/// `x` with five significant digits, without trailing zeros (integers exactly).
pub fn human(x: f64) -> String {
    if x.fract() == 0.0 && x.abs() < 1e15 {
        return format!("{}", x as i64);
    }
    let digits = (4 - x.abs().log10().floor() as i32).clamp(0, 12) as usize;
    let text = format!("{x:.digits$}");
    let text = if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.')
    } else {
        &text
    };
    text.to_string()
}
