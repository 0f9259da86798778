//! `scionc`: the Scion compiler driver.

fn main() {
    eprintln!("scionc: the driver is not built yet");
    std::process::exit(2);
}
