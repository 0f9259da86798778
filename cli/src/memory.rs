//! Peak memory per phase (`scion trace`'s `memory` line): the process's resident high-water mark
//! (`VmHWM` of /proc/self/status) read at the end of each phase and reset for the next (writing
//! 5 to /proc/self/clear_refs), so each phase reports the most memory the process held while it
//! ran, what came before included. Where /proc does not offer these (not Linux), nothing is
//! reported.

/// The phases' peaks so far.
pub struct Peaks {
    phases: Vec<(&'static str, u64)>,
}

/// The resident high-water mark in bytes.
fn high_water() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Resets the high-water mark to the current resident size.
fn reset() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

impl Peaks {
    /// Starts measuring (the first phase's peak counts from here).
    pub fn start() -> Peaks {
        reset();
        Peaks { phases: Vec::new() }
    }

    /// Ends phase `name`: records its peak and starts the next.
    pub fn mark(&mut self, name: &'static str) {
        if let Some(b) = high_water() {
            self.phases.push((name, b));
        }
        reset();
    }

    /// `compile 0.15 GiB, load 1.2 GiB, ...`, or `None` when nothing was measured.
    pub fn report(&self) -> Option<String> {
        if self.phases.is_empty() {
            return None;
        }
        let parts: Vec<String> = self
            .phases
            .iter()
            .map(|(n, b)| format!("{n} {:.2} GiB", *b as f64 / (1u64 << 30) as f64))
            .collect();
        Some(parts.join(", "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_large_allocation_shows_in_its_phase() {
        let mut p = Peaks::start();
        p.mark("before");
        let v = vec![1u8; 256 << 20];
        std::hint::black_box(&v);
        p.mark("allocating");
        drop(v);
        if let Some(r) = p.report() {
            let before = p.phases[0].1;
            let during = p.phases[1].1;
            assert!(during >= before + (200 << 20), "{r}");
        }
    }
}
