//! Compiles the C++ shim over Debian's libsumo (and again over libtraci, for sumo-gui) and
//! links `libsumocpp` and `libtracicpp`.
use std::path::Path;

fn main() {
    let header = Path::new("/usr/include/libsumo/libsumo.h");
    if !header.exists() {
        panic!(
            "libsumo headers not found at {}: install SUMO first (`make deps`, i.e. apt-get install sumo sumo-tools)",
            header.display()
        );
    }
    println!("cargo:rerun-if-changed=src/sumo/shim.cpp");
    println!("cargo:rerun-if-changed=src/sumo/shim_traci.cpp");
    println!("cargo:rerun-if-changed=build.rs");
    cc::Build::new()
        .cpp(true)
        .file("src/sumo/shim.cpp")
        .flag_if_supported("-std=c++17")
        .flag_if_supported("-Wno-deprecated-declarations")
        .warnings(false)
        .compile("bkpbs_sumo_shim");
    // The same shim over libtraci, which drives sumo-gui (`bkpbs episode --gui`).
    cc::Build::new()
        .cpp(true)
        .file("src/sumo/shim_traci.cpp")
        .flag_if_supported("-std=c++17")
        .flag_if_supported("-Wno-deprecated-declarations")
        .warnings(false)
        .compile("bkpbs_traci_shim");
    println!("cargo:rustc-link-lib=dylib=sumocpp");
    println!("cargo:rustc-link-lib=dylib=tracicpp");
}
