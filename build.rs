//! Sets `cfg(raylane_riscv_f)` on RISC-V targets whose cores have the F extension, so that
//! `Lane::sqrt` uses the `fsqrt.s` instruction there (src/lane.rs).
//!
//! Stable Rust does not expose `cfg(target_feature = "f")` for RISC-V (the feature is still
//! unstable as a cfg), so the extension is read from the target's name (`riscv32imafc-…`,
//! `riscv64gc-…`: an `f` or `g` in the base ISA letters), from the enabled target features
//! when the compiler reports them, and from `-C target-feature=+f`/`-f` in the rustflags. A
//! core without F, or a custom target not recognised here, gets `libm`'s correctly rounded
//! software root: the same bits, only slower.
use std::env;

fn main() {
    println!("cargo::rustc-check-cfg=cfg(raylane_riscv_f)");
    println!("cargo::rerun-if-changed=build.rs");
    let arch = env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default();
    if arch != "riscv32" && arch != "riscv64" {
        return;
    }
    let target = env::var("TARGET").unwrap_or_default();
    let isa = target
        .split('-')
        .next()
        .unwrap_or("")
        .trim_start_matches(&arch)
        .split(['_', 'z', 'x'])
        .next()
        .unwrap_or("");
    let mut f = isa.contains('f') || isa.contains('g');
    let features = env::var("CARGO_CFG_TARGET_FEATURE").unwrap_or_default();
    f |= features.split(',').any(|x| x == "f");
    let flags = env::var("CARGO_ENCODED_RUSTFLAGS").unwrap_or_default();
    for word in flags.split(['\x1f', ',', '=', ' ']) {
        match word {
            "+f" | "+d" => f = true,
            "-f" => f = false,
            _ => {}
        }
    }
    if f {
        println!("cargo::rustc-cfg=raylane_riscv_f");
    }
}
