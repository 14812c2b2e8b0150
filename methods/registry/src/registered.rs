// The reading of the method registry in `methods/src/lib.rs`, shared by this crate's build script
// (which includes this file) and its library (`registered`, tested there).

/// The comment lines that open and close the registry in `methods/src/lib.rs`.
pub const START: &str = "// Method registry";
pub const END: &str = "// End of the method registry";

/// The registered module names of `lib`, in order; `Err` names the line that is not one.
pub fn registered(lib: &str) -> Result<Vec<String>, String> {
    let mut lines = lib.lines().enumerate();
    lines
        .by_ref()
        .find(|(_, l)| l.trim_start().starts_with(START))
        .ok_or_else(|| format!("no `{START}` comment opens the method registry"))?;
    let mut names = Vec::new();
    for (index, line) in lines {
        let line = line.trim();
        if line.starts_with(END) {
            return Ok(names);
        }
        if line.is_empty() || line.starts_with("//") {
            continue;
        }
        let name = line
            .strip_prefix("pub mod ")
            .and_then(|rest| rest.strip_suffix(';'))
            .filter(|name| {
                !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
            })
            .ok_or_else(|| {
                format!(
                    "line {}: `{line}`: the method registry holds only `pub mod <name>;` lines",
                    index + 1
                )
            })?;
        names.push(name.to_string());
    }
    Err(format!("no `{END}` comment closes the method registry"))
}
