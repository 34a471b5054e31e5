#!/usr/bin/env python3
"""Builds the Mega 2560 board image with Debian's rustc 1.63, crate by crate.

Why not cargo: rustup cannot install an AVR standard library here, Debian's cargo 1.65 cannot
read today's lock files or reach the index, and rustup's cargo passes flags rustc 1.63 does not
know. So this script does the part of cargo that is needed, and nothing else:

1. `cargo metadata` (rustup's cargo) on this crate's manifest and its own Cargo.lock: which
   packages, which versions (downloaded to ~/.cargo/registry if missing), which features, which
   dependencies under which names;
2. a sysroot for the target `avr-atmega2560.json`: `core` from Debian's rust-src, and an empty
   `compiler_builtins` (the routines come from avr-gcc's libgcc at link time);
3. each library with `rustc --crate-type rlib`, dependencies first, then the binary, linked by
   avr-gcc (`-mmcu=atmega2560`, its start-up code and vector table);
4. the Intel HEX file for avrdude beside the ELF.

Outputs land in OUT (argument 1); every step is skipped when its inputs have not changed.
Prints the ELF's path as its last line.
"""
import hashlib
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
TARGET = "avr-atmega2560"
RUSTC = os.environ.get("CRACKBOT_AVR_RUSTC", "/usr/bin/rustc")
RUST_SRC = Path("/usr/lib/rustlib/src/rust/library")
FLAGS = ["-C", "opt-level=3", "-C", "panic=abort", "-C", "debuginfo=1"]

# Build scripts are not run: each package that has one is listed with the `--cfg`s its script
# would print for this target (read from the script; heapless 0.8 only probes atomics and ARM
# exclusives, which AVR has neither of).
BUILD_SCRIPT_CFGS = {"heapless": []}
# Language features a package uses that were stabilised after rustc 1.63 (generic associated
# types in 1.65, `&mut` in `const fn` in 1.83): enabled with RUSTC_BOOTSTRAP for that package.
UNSTABLE_FEATURES = {"crc": ["generic_associated_types", "const_mut_refs"]}


class BuildError(Exception):
    pass


def run(cmd, **kw):
    env = dict(os.environ, RUSTC_BOOTSTRAP="1")
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, **kw)
    if proc.returncode != 0:
        raise BuildError(f"{' '.join(map(str, cmd))}\n{proc.stdout}{proc.stderr}")
    if proc.stderr.strip():
        sys.stderr.write(proc.stderr)
    return proc.stdout


def digest(*parts):
    h = hashlib.sha256()
    for p in parts:
        if isinstance(p, Path):
            h.update(p.read_bytes())
        else:
            h.update(str(p).encode())
    return h.hexdigest()[:16]


def up_to_date(stamp: Path, key: str) -> bool:
    return stamp.exists() and stamp.read_text() == key


def sysroot(out: Path) -> Path:
    root = out / "sysroot"
    lib = root / "lib" / "rustlib" / TARGET / "lib"
    key = digest(run([RUSTC, "-vV"]), HERE / f"{TARGET}.json", HERE / "compiler_builtins.rs", FLAGS)
    stamp = root / "stamp"
    if up_to_date(stamp, key):
        return root
    shutil.rmtree(root, ignore_errors=True)
    lib.mkdir(parents=True)
    print(f"building core for {TARGET} (rustc 1.63, about 15 s)", file=sys.stderr)
    common = ["--edition", "2021", "--crate-type", "rlib", "--target", str(HERE / f"{TARGET}.json")]
    common += FLAGS + ["-Z", "force-unstable-if-unmarked"]
    run([RUSTC, *common, "--crate-name", "core", str(RUST_SRC / "core" / "src" / "lib.rs"),
         "-o", str(lib / "libcore.rlib")])
    run([RUSTC, *common, "--crate-name", "compiler_builtins", "--sysroot", str(root),
         str(HERE / "compiler_builtins.rs"), "-o", str(lib / "libcompiler_builtins.rlib")])
    stamp.write_text(key)
    return root


def metadata():
    text = subprocess.run(
        ["cargo", "metadata", "--format-version", "1", "--locked",
         "--manifest-path", str(HERE / "Cargo.toml")],
        capture_output=True, text=True)
    if text.returncode != 0:
        raise BuildError(f"cargo metadata failed:\n{text.stderr}")
    return json.loads(text.stdout)


def build_order(meta):
    """Packages in dependency order, each with its lib/bin target, features and extern deps."""
    packages = {p["id"]: p for p in meta["packages"]}
    nodes = {n["id"]: n for n in meta["resolve"]["nodes"]}
    order, seen = [], set()

    def visit(pid):
        if pid in seen:
            return
        seen.add(pid)
        node = nodes[pid]
        deps = []
        for dep in node["deps"]:
            if any(k["kind"] is None for k in dep["dep_kinds"]):
                visit(dep["pkg"])
                deps.append((dep["name"], dep["pkg"]))
        order.append((packages[pid], node["features"], deps))

    visit(meta["resolve"]["root"])
    return order


def compile_package(pkg, features, deps, out, root, built):
    name = pkg["name"]
    kinds = {k for t in pkg["targets"] for k in t["kind"]}
    if "proc-macro" in kinds:
        raise BuildError(f"{name} is a procedural macro: it cannot be built for the board here")
    if "custom-build" in kinds and name not in BUILD_SCRIPT_CFGS:
        raise BuildError(f"{name} has a build script this driver does not know: add it to "
                         "BUILD_SCRIPT_CFGS with the cfgs it prints for AVR")
    is_bin = pkg["id"] == built["root"]
    target = next(t for t in pkg["targets"]
                  if ("bin" in t["kind"] if is_bin else ("lib" in t["kind"] or "rlib" in t["kind"])))
    crate = target["name"].replace("-", "_")
    args = ["--edition", pkg["edition"], "--crate-name", crate,
            "--target", str(HERE / f"{TARGET}.json"), "--sysroot", str(root),
            "-L", f"dependency={out / 'deps'}", *FLAGS]
    args += ["--crate-type", "bin" if is_bin else "rlib"]
    for f in features:
        args += ["--cfg", f'feature="{f}"']
    for cfg in BUILD_SCRIPT_CFGS.get(name, []):
        args += ["--cfg", cfg]
    for feat in UNSTABLE_FEATURES.get(name, []):
        args += [f"-Zcrate-attr=feature({feat})"]
    # Others' crates: their lints are theirs. Ours: no warnings (rustc 1.63's lint set).
    args += ["--cap-lints", "allow"] if pkg["source"] else ["-D", "warnings"]
    for extern, dep_id in deps:
        args += ["--extern", f"{extern}={built[dep_id]}"]
    if is_bin:
        output = out / f"{pkg['name']}.elf"
        # avr-libc (memcpy, memset, memcmp, abort), then libgcc for what avr-libc calls.
        args += ["-C", "lto=fat", "-C", "link-arg=-Wl,--gc-sections", "-C", "link-arg=-lc", "-C", "link-arg=-lgcc"]
    else:
        output = out / "deps" / f"lib{crate}.rlib"
    sources = sorted(Path(target["src_path"]).parent.rglob("*.rs"))
    key = digest(*args, *sources, *(Path(built[d]) for _, d in deps))
    stamp = output.with_suffix(output.suffix + ".stamp")
    if not up_to_date(stamp, key):
        print(f"   compiling {name} {pkg['version']}", file=sys.stderr)
        run([RUSTC, *args, target["src_path"], "-o", str(output)])
        stamp.write_text(key)
    built[pkg["id"]] = str(output)
    return output


def main():
    out = Path(sys.argv[1]).resolve() if len(sys.argv) > 1 else HERE / "target"
    (out / "deps").mkdir(parents=True, exist_ok=True)
    root = sysroot(out)
    meta = metadata()
    built = {"root": meta["resolve"]["root"]}
    elf = None
    for pkg, features, deps in build_order(meta):
        elf = compile_package(pkg, features, deps, out, root, built)
    hex_file = elf.with_suffix(".hex")
    if not hex_file.exists() or hex_file.stat().st_mtime < elf.stat().st_mtime:
        run(["avr-objcopy", "-O", "ihex", "-R", ".eeprom", str(elf), str(hex_file)])
        sys.stderr.write(run(["avr-size", "--format=avr", "--mcu=atmega2560", str(elf)]))
    print(elf)


if __name__ == "__main__":
    try:
        main()
    except BuildError as e:
        sys.exit(f"firmware build failed: {e}")
