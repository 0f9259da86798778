//! The results file of `scion explore` (CSV, one row per measurement, [`ROW_FIELDS`]) and the
//! peers file its plots read ([`crate::plot::PEER_FIELDS`]): reading with the header checked,
//! writing fields, the key a rerun skips, and the provenance every row carries (machine,
//! commit, toolchain, date).

use crate::CliError;
use std::collections::BTreeMap;
use std::path::Path;

/// The CSV's columns, in order.
pub const ROW_FIELDS: [&str; 24] = [
    "commit",
    "machine",
    "cpus",
    "toolchain",
    "date",
    "scene",
    "triangles",
    "kind",
    "queries",
    "n",
    "backend",
    "threads",
    "builder",
    "layout",
    "bytes",
    "bytes_per_triangle",
    "seconds",
    "ns_per_query",
    "mqueries_per_s",
    "check",
    "area_inflation",
    "extra_box_tests",
    "extra_node_visits",
    "runs",
];

/// The columns that identify a measurement (a rerun skips a key already present).
const KEY_FIELDS: [&str; 8] = [
    "scene", "kind", "queries", "n", "backend", "threads", "builder", "layout",
];

/// One measurement's fields, by column name.
pub type Row = BTreeMap<String, String>;

/// Reads the rows of a results CSV (`None` when there is no such file).
pub fn read_rows(path: &Path) -> Result<Option<Vec<Row>>, CliError> {
    read_csv(
        path,
        &ROW_FIELDS,
        "a results file of this version of `scion explore`",
    )
}

/// Reads the rows of a CSV whose header must be `fields` (`None` when there is no such file);
/// `what` names the file's kind in the error when it is not.
pub fn read_csv(path: &Path, fields: &[&str], what: &str) -> Result<Option<Vec<Row>>, CliError> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => {
            return Err(CliError::new(format!(
                "cannot read {}: {e}",
                path.display()
            )))
        }
    };
    let mut lines = text.lines();
    let Some(header) = lines.next() else {
        return Ok(Some(Vec::new()));
    };
    let names: Vec<&str> = header.split(',').collect();
    if names != fields {
        return Err(CliError::new(format!(
            "{}: not {what} (its header is `{header}`, not `{}`)",
            path.display(),
            fields.join(",")
        )));
    }
    let mut rows = Vec::new();
    for (k, line) in lines.enumerate() {
        let cells = split_csv(line);
        if cells.len() != names.len() {
            return Err(CliError::new(format!(
                "{}:{}: {} fields where the header has {}",
                path.display(),
                k + 2,
                cells.len(),
                names.len()
            )));
        }
        rows.push(names.iter().map(|n| n.to_string()).zip(cells).collect());
    }
    Ok(Some(rows))
}

/// A CSV line's fields (double quotes around a field with a comma or a quote, `""` inside).
pub(crate) fn split_csv(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    out.push(cur);
    out
}

pub(crate) fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\"").replace('\n', " "))
    } else {
        s.to_string()
    }
}

pub(crate) fn key(row: &Row) -> Vec<String> {
    KEY_FIELDS
        .iter()
        .map(|f| row.get(*f).cloned().unwrap_or_default())
        .collect()
}

/// The machine, the commit and the toolchain, for every row.
pub(crate) struct Provenance {
    pub commit: String,
    pub machine: String,
    pub cpus: String,
    pub toolchain: String,
}

pub(crate) fn provenance() -> Provenance {
    // The commit of the checkout the binary was built in (it lives in its target folder),
    // else of the current folder.
    let exe_dir = std::env::current_exe()
        .ok()
        .and_then(|p| p.parent().map(Path::to_path_buf));
    let commit = exe_dir
        .into_iter()
        .chain(std::iter::once(std::path::PathBuf::from(".")))
        .find_map(|dir| {
            std::process::Command::new("git")
                .arg("-C")
                .arg(&dir)
                .args(["rev-parse", "--short", "HEAD"])
                .output()
                .ok()
                .filter(|o| o.status.success())
                .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into());
    let machine = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    Provenance {
        commit,
        machine,
        cpus: cpus.to_string(),
        toolchain: format!(
            "scion {} LLVM {}",
            env!("CARGO_PKG_VERSION"),
            scion_llvm::llvm_version()
        ),
    }
}

/// The time now, `YYYY-MM-DDTHH:MM:SSZ`.
pub(crate) fn now_utc() -> String {
    let s = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (days, rem) = (s / 86_400, s % 86_400);
    // Civil from days (Howard Hinnant's algorithm).
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_fields_round_trip() {
        let cells = ["a", "b,c", "say \"hi\"", ""];
        let line: Vec<String> = cells.iter().map(|c| csv_field(c)).collect();
        assert_eq!(split_csv(&line.join(",")), cells);
    }

    #[test]
    fn dates_are_civil() {
        let d = now_utc();
        assert_eq!(d.len(), 20, "{d}");
        assert!(d.starts_with("20"), "{d}");
    }
}
