//! Reading a PTX module's kernels on the host: the `.entry` names and each parameter's size and
//! kind, so a launch's arguments are checked against what the kernel really takes before the
//! driver sees them (a wrong size there is silent garbage on the device, not an error). Also
//! the PTX's `.version` and `.target`, for messages. Input: PTX text as LLVM's NVPTX back end
//! prints it; output: [`PtxEntry`]s.

/// One parameter of a kernel.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PtxParam {
    /// Its name in the PTX (`k_param_0`).
    pub name: String,
    /// Its size in bytes (the whole array for `.b8 x[N]`).
    pub bytes: usize,
    /// A `.f16`/`.f32`/`.f64` parameter.
    pub is_float: bool,
    /// A byte array (an aggregate passed by value).
    pub array: bool,
}

impl PtxParam {
    /// "a 4-byte integer", "an 8-byte float", "a 16-byte array".
    pub fn describe(&self) -> String {
        let kind = if self.array {
            "array"
        } else if self.is_float {
            "float"
        } else {
            "integer"
        };
        let article = if self.bytes == 8 { "an" } else { "a" };
        format!("{article} {}-byte {kind}", self.bytes)
    }
}

/// One kernel (`.entry`) of a module.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PtxEntry {
    /// Its name.
    pub name: String,
    /// Its parameters in order.
    pub params: Vec<PtxParam>,
}

/// The kernels a PTX module declares, in order. Parameters the parser does not understand are
/// reported as an error naming the kernel and the text.
pub fn entries(ptx: &str) -> Result<Vec<PtxEntry>, String> {
    let mut out = Vec::new();
    let mut rest = ptx;
    while let Some(at) = find_entry(rest) {
        let after = &rest[at + ".entry".len()..];
        let open = after
            .find('(')
            .ok_or_else(|| "a .entry without a parameter list".to_string())?;
        let name = after[..open].trim().to_string();
        // A kernel without parameters may be printed without parentheses: `.entry k {`.
        let brace = after.find('{').unwrap_or(after.len());
        if brace < open {
            let name = after[..brace].trim().to_string();
            out.push(PtxEntry {
                name,
                params: Vec::new(),
            });
            rest = &after[brace..];
            continue;
        }
        let close = after[open..]
            .find(')')
            .map(|c| open + c)
            .ok_or_else(|| format!("kernel `{name}`: unterminated parameter list"))?;
        let mut params = Vec::new();
        for decl in after[open + 1..close].split(',') {
            let decl = decl.trim();
            if decl.is_empty() {
                continue;
            }
            params.push(param(decl).map_err(|e| format!("kernel `{name}`: {e}"))?);
        }
        out.push(PtxEntry { name, params });
        rest = &after[close..];
    }
    Ok(out)
}

/// The offset of the next `.entry` directive that starts a declaration (not inside a
/// comment).
fn find_entry(text: &str) -> Option<usize> {
    let mut from = 0;
    while let Some(i) = text[from..].find(".entry") {
        let at = from + i;
        let line_start = text[..at].rfind('\n').map_or(0, |n| n + 1);
        let line = &text[line_start..at];
        let next = text[at + 6..].chars().next();
        if !line.contains("//") && next.is_some_and(char::is_whitespace) {
            return Some(at);
        }
        from = at + 6;
    }
    None
}

/// One `.param` declaration: `.param .u64 .ptr .align 1 k_param_0`, `.param .u32 k_param_1`,
/// `.param .align 8 .b8 k_param_2[16]`.
fn param(decl: &str) -> Result<PtxParam, String> {
    let mut words = decl.split_whitespace();
    if words.next() != Some(".param") {
        return Err(format!("unexpected parameter `{decl}`"));
    }
    let mut ty = None;
    let mut name = None;
    let mut skip_number = false;
    for w in words {
        if skip_number {
            skip_number = false;
            continue;
        }
        match w {
            ".align" => skip_number = true,
            ".ptr" | ".global" | ".const" | ".shared" | ".local" => {}
            _ if w.starts_with('.') => ty = Some(&w[1..]),
            _ => name = Some(w),
        }
    }
    let ty = ty.ok_or_else(|| format!("no type in `{decl}`"))?;
    let name = name.ok_or_else(|| format!("no name in `{decl}`"))?;
    let (is_float, bits) = match ty.split_at(1) {
        ("f", b) => (true, b),
        ("u" | "s" | "b", b) => (false, b),
        _ => return Err(format!("unknown type `.{ty}` in `{decl}`")),
    };
    let bits: usize = bits
        .parse()
        .map_err(|_| format!("unknown type `.{ty}` in `{decl}`"))?;
    let elem = bits.div_ceil(8);
    match name.split_once('[') {
        Some((n, count)) => {
            let count: usize = count
                .trim_end_matches(']')
                .parse()
                .map_err(|_| format!("bad array size in `{decl}`"))?;
            Ok(PtxParam {
                name: n.to_string(),
                bytes: elem * count,
                is_float,
                array: true,
            })
        }
        None => Ok(PtxParam {
            name: name.to_string(),
            bytes: elem,
            is_float,
            array: false,
        }),
    }
}

/// The value of a module-level directive such as `.version` or `.target`.
pub fn directive<'a>(ptx: &'a str, name: &str) -> Option<&'a str> {
    ptx.lines().find_map(|l| {
        let l = l.trim();
        l.strip_prefix(name)
            .filter(|r| r.starts_with(char::is_whitespace))
            .map(str::trim)
    })
}

/// Whether PTX whose `.target` is `target` (`sm_90`, `sm_90a`, `sm_100f`) can run on a device
/// of compute capability `cc`: the driver JIT-compiles PTX for a GPU onto the same or a newer
/// one, arch-specific PTX (`a`) only onto exactly that GPU, family PTX (`f`) onto the same
/// major version with at least that minor. `Err` says why not in one sentence; a target this
/// function cannot read is left to the driver (`Ok`).
pub fn target_runs_on(target: &str, cc: (i32, i32)) -> Result<(), String> {
    let Some(rest) = target
        .split(',')
        .next()
        .and_then(|t| t.trim().strip_prefix("sm_"))
    else {
        return Ok(());
    };
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    let suffix = &rest[digits.len()..];
    let (Some(minor), Ok(major)) = (
        digits.chars().last().and_then(|c| c.to_digit(10)),
        digits[..digits.len().saturating_sub(1)].parse::<i32>(),
    ) else {
        return Ok(());
    };
    let need = (major, minor as i32);
    let fits = match suffix {
        "" => need <= cc,
        "a" => need == cc,
        "f" => need.0 == cc.0 && need.1 <= cc.1,
        _ => return Ok(()),
    };
    if fits {
        return Ok(());
    }
    let rule = match suffix {
        "a" => "arch-specific PTX runs only on that GPU",
        "f" => "family PTX runs only on GPUs of that major version",
        _ => "PTX for a GPU runs on it and newer ones, not on older ones",
    };
    Err(format!(
        "the PTX is for {target} but the device is sm_{}{} ({rule}); compile for it with \
         --cpu sm_{}{}",
        cc.0, cc.1, cc.0, cc.1
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn targets_run_on_the_same_or_newer_gpus() {
        let h100 = (9, 0);
        for ok in [
            "sm_75", "sm_80", "sm_89", "sm_90", "sm_90a", "garbage", "sm_x",
        ] {
            assert_eq!(target_runs_on(ok, h100), Ok(()), "{ok}");
        }
        let e = target_runs_on("sm_100", h100).unwrap_err();
        assert_eq!(
            e,
            "the PTX is for sm_100 but the device is sm_90 (PTX for a GPU runs on it and newer \
             ones, not on older ones); compile for it with --cpu sm_90"
        );
        assert!(target_runs_on("sm_90a", (10, 0))
            .unwrap_err()
            .contains("arch-specific"));
        assert_eq!(target_runs_on("sm_100f", (10, 3)), Ok(()));
        assert!(target_runs_on("sm_100f", (12, 0))
            .unwrap_err()
            .contains("family"));
        assert_eq!(target_runs_on("sm_120", (12, 1)), Ok(()));
        assert!(target_runs_on("sm_121", (12, 0)).is_err());
    }

    const LLC_OUTPUT: &str = "//\n// Generated by LLVM NVPTX Back-End\n//\n\n.version 6.3\n\
        .target sm_75\n.address_size 64\n\n\t// .globl\tk    // -- Begin function k\n\
        .visible .entry k(\n\t.param .u64 .ptr .align 1 k_param_0,\n\t.param .u32 k_param_1,\n\
        \t.param .u64 k_param_2\n)\n{\n\tret;\n}\n\
        .visible .entry two(\n\t.param .align 8 .b8 two_param_0[16],\n\t.param .f32 two_param_1\n)\n\
        {\n\tret;\n}\n.visible .entry none()\n{\n\tret;\n}\n";

    #[test]
    fn reads_entries_and_parameters() {
        let es = entries(LLC_OUTPUT).unwrap();
        let names: Vec<&str> = es.iter().map(|e| e.name.as_str()).collect();
        assert_eq!(names, ["k", "two", "none"]);
        let sizes: Vec<usize> = es[0].params.iter().map(|p| p.bytes).collect();
        assert_eq!(sizes, [8, 4, 8]);
        assert_eq!(es[0].params[0].name, "k_param_0");
        assert_eq!(
            es[1].params[0],
            PtxParam {
                name: "two_param_0".into(),
                bytes: 16,
                is_float: false,
                array: true
            }
        );
        assert!(es[1].params[1].is_float);
        assert_eq!(es[1].params[1].describe(), "a 4-byte float");
        assert!(es[2].params.is_empty());
        assert_eq!(directive(LLC_OUTPUT, ".version"), Some("6.3"));
        assert_eq!(directive(LLC_OUTPUT, ".target"), Some("sm_75"));
    }

    #[test]
    fn unknown_parameters_are_errors() {
        let e = entries(".entry k(\n.param .zz9 k_param_0\n)\n{\n}").unwrap_err();
        assert_eq!(
            e,
            "kernel `k`: unknown type `.zz9` in `.param .zz9 k_param_0`"
        );
        assert!(entries("no kernels here").unwrap().is_empty());
    }
}
