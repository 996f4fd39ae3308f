//! Compiles the C++ shim over libsumo (and again over libtraci, for sumo-gui), links
//! `libsumocpp` and `libtracicpp`, and records which SUMO it was built against.
//!
//! SUMO is found the way SUMO users expect: `$SUMO_HOME` when it holds libsumo's headers (the
//! `eclipse-sumo` wheel's `…/site-packages/sumo`, or SUMO built from source), else Debian's
//! system paths (`/usr/include/libsumo` and the linker's default directories; Debian's own
//! SUMO_HOME, `/usr/share/sumo`, holds no headers). A SUMO under `$SUMO_HOME` is linked with a
//! run-time path to its library directory, because every libsumo has the same soname: without
//! it the binary would load whichever libsumocpp the system has, silently another version.
//!
//! The version is asked of the library itself: a probe linked like the shim prints libsumo's
//! `Simulation::getVersion()`. It becomes `BKPBS_SUMO_VERSION`, which `sumo::version` compares
//! with the library a run actually loads.
use std::path::{Path, PathBuf};
use std::process::Command;

/// Where libsumo's headers and libraries are, and a name for the error messages.
struct Sumo {
    /// Directory holding `libsumo/libsumo.h`; `None`: the compiler's default (Debian).
    include: Option<PathBuf>,
    /// Directory holding `libsumocpp.so`; `None`: the linker's default (Debian).
    lib: Option<PathBuf>,
    /// Where it was found, for messages.
    origin: String,
}

const DEBIAN_HEADER: &str = "/usr/include/libsumo/libsumo.h";

fn main() {
    println!("cargo:rerun-if-changed=src/sumo/shim.cpp");
    println!("cargo:rerun-if-changed=src/sumo/shim_traci.cpp");
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=SUMO_HOME");
    record_commit();
    let sumo = find_sumo();
    let version = probe_version(&sumo);
    compile_shim(&sumo, "src/sumo/shim.cpp", "bkpbs_sumo_shim");
    // The same shim over libtraci, which drives sumo-gui (`bkpbs episode --gui`).
    compile_shim(&sumo, "src/sumo/shim_traci.cpp", "bkpbs_traci_shim");
    if let Some(lib) = &sumo.lib {
        println!("cargo:rustc-link-search=native={}", lib.display());
        println!("cargo:rustc-link-arg=-Wl,-rpath,{}", lib.display());
        // For dependants (the Python bindings' cdylib), as DEP_SUMOCPP_LIB_DIR.
        println!("cargo:lib_dir={}", lib.display());
    }
    println!("cargo:rustc-link-lib=dylib=sumocpp");
    println!("cargo:rustc-link-lib=dylib=tracicpp");
    println!("cargo:rustc-env=BKPBS_SUMO_VERSION={version}");
    println!("cargo:version={version}");
    if let Some(home) = std::env::var_os("SUMO_HOME").filter(|_| sumo.lib.is_some()) {
        println!(
            "cargo:rustc-env=BKPBS_SUMO_HOME={}",
            Path::new(&home).display()
        );
    }
}

/// The commit the sources are built from, as `BKPBS_COMMIT` (what a campaign cell records of
/// its build): `$BKPBS_COMMIT` if set (a build from a source archive), else git's `HEAD`, else
/// `unknown`. The build script runs again when `HEAD` moves: its file and the ref it names
/// are watched (only existing files: cargo reruns a script on every build for a missing one).
fn record_commit() {
    println!("cargo:rerun-if-env-changed=BKPBS_COMMIT");
    let given = std::env::var("BKPBS_COMMIT").ok().filter(|c| !c.is_empty());
    let commit = given.or_else(git_head).unwrap_or_else(|| "unknown".into());
    println!("cargo:rustc-env=BKPBS_COMMIT={commit}");
}

/// `HEAD`'s commit, watching the files that move it; `None` outside a git checkout.
fn git_head() -> Option<String> {
    let git = |args: &[&str]| {
        let out = Command::new("git").args(args).output().ok()?;
        let text = String::from_utf8(out.stdout).ok()?;
        out.status.success().then(|| text.trim().to_string())
    };
    let head = git(&["rev-parse", "HEAD"])?;
    let mut watched = vec!["HEAD".to_string(), "packed-refs".to_string()];
    watched.extend(git(&["symbolic-ref", "-q", "HEAD"]));
    for name in watched {
        if let Some(path) = git(&["rev-parse", "--path-format=absolute", "--git-path", &name]) {
            if Path::new(&path).exists() {
                println!("cargo:rerun-if-changed={path}");
            }
        }
    }
    Some(head)
}

/// `$SUMO_HOME` with headers, else Debian's system paths; a build script's panic is the one
/// message a user sees, so it says where it looked.
fn find_sumo() -> Sumo {
    if let Some(home) = std::env::var_os("SUMO_HOME").map(PathBuf::from) {
        let include = home.join("include");
        if include.join("libsumo/libsumo.h").is_file() {
            let lib = ["lib64", "lib"]
                .iter()
                .map(|d| home.join(d))
                .find(|d| d.join("libsumocpp.so").is_file())
                .unwrap_or_else(|| {
                    panic!(
                        "SUMO_HOME={} has libsumo's headers but no lib64/ or lib/ with libsumocpp.so",
                        home.display()
                    )
                });
            let origin = format!("SUMO_HOME={}", home.display());
            return Sumo {
                include: Some(include),
                lib: Some(lib),
                origin,
            };
        }
    }
    if !Path::new(DEBIAN_HEADER).is_file() {
        panic!(
            "libsumo's headers not found: neither $SUMO_HOME/include/libsumo (SUMO_HOME={}) nor {DEBIAN_HEADER}; \
             install SUMO first (`make deps` for Debian's package, `make deps SUMO=pip` for the eclipse-sumo wheel)",
            std::env::var("SUMO_HOME").unwrap_or_else(|_| "unset".into())
        );
    }
    Sumo {
        include: None,
        lib: None,
        origin: "Debian's system paths".into(),
    }
}

fn compile_shim(sumo: &Sumo, file: &str, name: &str) {
    let mut build = cc::Build::new();
    build
        .cpp(true)
        .file(file)
        .flag_if_supported("-std=c++17")
        .flag_if_supported("-Wno-deprecated-declarations")
        .warnings(false);
    if let Some(include) = &sumo.include {
        build.include(include);
    }
    build.compile(name);
}

/// Compiles and runs a program printing `libsumo::Simulation::getVersion()`, linked like the
/// shim; returns the version without its "SUMO " prefix (e.g. `1.15.0`).
fn probe_version(sumo: &Sumo) -> String {
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let source = out.join("sumo_version.cpp");
    let program = out.join("sumo_version");
    std::fs::write(
        &source,
        "#include <libsumo/libsumo.h>\n#include <iostream>\n\
         int main() { std::cout << libsumo::Simulation::getVersion().second; }\n",
    )
    .expect("OUT_DIR is writable");
    let mut cc = cc::Build::new().cpp(true).get_compiler().to_command();
    cc.arg("-std=c++17").arg(&source).arg("-o").arg(&program);
    if let Some(include) = &sumo.include {
        cc.arg(format!("-I{}", include.display()));
    }
    if let Some(lib) = &sumo.lib {
        cc.arg(format!("-L{}", lib.display()));
        cc.arg(format!("-Wl,-rpath,{}", lib.display()));
    }
    cc.arg("-lsumocpp");
    run(
        cc,
        &format!("compiling a libsumo probe against {}", sumo.origin),
    );
    let printed = run(
        Command::new(&program),
        &format!("running the libsumo probe of {}", sumo.origin),
    );
    printed.trim().trim_start_matches("SUMO ").to_string()
}

/// Runs a command of the build, returning its standard output; a failure panics with its output.
fn run(mut command: Command, what: &str) -> String {
    let output = command
        .output()
        .unwrap_or_else(|e| panic!("{what}: cannot run {command:?}: {e}"));
    if !output.status.success() {
        panic!(
            "{what} failed ({}): {}",
            output.status,
            String::from_utf8_lossy(&output.stderr).trim()
        );
    }
    String::from_utf8_lossy(&output.stdout).into_owned()
}
