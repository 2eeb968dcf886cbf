"""Checks the FMI 3.0 C types that fmu/src/ffi.rs writes by hand against the standard's
headers (fmi3Functions.h, as shipped by fmpy), with a C compile.

From the Rust source it reads every exported function's signature, the `Status` enum and
the `LogMessage` callback type (fmu/src/instance.rs), translates them to C and compiles,
with the headers included first:

- each implemented function redeclared with its Rust signature: a C compiler refuses a
  redeclaration whose return or parameter types differ ("conflicting types");
- `Status`'s discriminants equal fmi3OK … fmi3Fatal, and the sizes of fmi3Boolean,
  fmi3ValueReference, fmi3Float64 and fmi3Status are Rust's bool, u32, f64 and repr(C) enum;
- the `logMessage` callback type is fmi3LogMessageCallback;
- every function of fmi3Functions.h is exported (importers resolve them all), and those
  exported as "unsupported" (first argument only, returning fmi3Error) return fmi3Status
  and take the instance first.

    .venv/bin/python scripts/check_fmi_header.py     (run by scripts/test.sh; needs gcc or cc)

Exits non-zero, naming the problem, if a type differs, the headers or the compiler are
missing: it never passes without having compiled the check.
"""
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
FFI = ROOT / "fmu" / "src" / "ffi.rs"
INSTANCE = ROOT / "fmu" / "src" / "instance.rs"

# Rust types of the FFI to C; `Status` becomes fmi3Status once its values are checked
RUST_TO_C = {
    "*mut c_void": "void*",
    "*const c_void": "const void*",
    "*const c_char": "const char*",
    "*const *const c_char": "const char* const*",
    "bool": "bool",
    "f64": "double",
    "u32": "uint32_t",
    "usize": "size_t",
    "c_int": "int",
    "*const u32": "const uint32_t*",
    "*mut f64": "double*",
    "*const f64": "const double*",
    "*mut bool": "bool*",
    "Status": "fmi3Status",
    "Option<LogMessage>": "loam_LogMessage",
    "Option<IntermediateUpdate>": "loam_IntermediateUpdate",
    "Option<ClockUpdate>": "loam_ClockUpdate",
    "Option<Preemption>": "loam_Preemption",
}
STATUS = {"Ok": "fmi3OK", "Warning": "fmi3Warning", "Discard": "fmi3Discard", "Error": "fmi3Error", "Fatal": "fmi3Fatal"}


def fail(message):
    print(f"check_fmi_header: {message}", file=sys.stderr)
    sys.exit(1)


def c_type(rust):
    rust = " ".join(rust.split())
    if rust not in RUST_TO_C:
        fail(f"no C translation for the Rust type `{rust}` (add it to RUST_TO_C)")
    return RUST_TO_C[rust]


def split_params(text):
    """Parameters `name: Type` at depth 0 (no commas inside <> or ())."""
    params, depth, current = [], 0, ""
    for ch in text:
        if ch in "<(":
            depth += 1
        elif ch in ">)":
            depth -= 1
        if ch == "," and depth == 0:
            params.append(current)
            current = ""
        else:
            current += ch
    if current.strip():
        params.append(current)
    return [p.split(":", 1) for p in (p.strip() for p in params) if p]


def c_prototype(name, params, ret):
    args = ", ".join(f"{c_type(t)} {n.strip()}" for n, t in params) or "void"
    return f"{c_type(ret) if ret else 'void'} {name}({args})"


def rust_functions(source):
    pattern = re.compile(r'pub (?:unsafe )?extern "C" fn (\w+)\((.*?)\)\s*(?:->\s*([^{]+?))?\s*\{', re.S)
    return [(m.group(1), split_params(m.group(2)), (m.group(3) or "").strip()) for m in pattern.finditer(source)]


def callback_types(source):
    """`pub type NAME = [unsafe] extern "C" fn(params) [-> ret];` as C typedefs."""
    out = []
    for m in re.finditer(r'pub type (\w+) =\s*(?:unsafe )?extern "C" fn\((.*?)\)\s*(?:->\s*([^;]+))?;', source, re.S):
        name, params, ret = m.group(1), split_params(m.group(2)), (m.group(3) or "").strip()
        args = ", ".join(c_type(t) for _, t in params) or "void"
        out.append((name, f"typedef {c_type(ret) if ret else 'void'} (*loam_{name})({args});"))
    return out


def main():
    try:
        import fmpy
    except ImportError:
        fail("fmpy is not installed (scripts/test.sh installs it into .venv)")
    headers = pathlib.Path(fmpy.__file__).parent / "c-code"
    if not (headers / "fmi3Functions.h").is_file():
        fail(f"no fmi3Functions.h in {headers}")
    compiler = shutil.which("gcc") or shutil.which("cc")
    if not compiler:
        fail("no C compiler (gcc or cc) on PATH")

    ffi, instance = FFI.read_text(), INSTANCE.read_text()
    functions = rust_functions(ffi)
    status = re.search(r"#\[repr\(C\)\]\s*pub enum Status \{(.*?)\}", instance, re.S)
    if not status:
        fail("no #[repr(C)] enum Status in fmu/src/instance.rs")
    values = re.findall(r"(\w+) = (\d+),", status.group(1))
    unsupported = re.search(r"unsupported!\((.*?)\);", ffi, re.S)
    unsupported = re.findall(r"fmi3\w+", unsupported.group(1)) if unsupported else []

    header_text = "".join(p.read_text() for p in sorted(headers.glob("fmi3*.h")))
    declared = set(re.findall(r"FMI3_Export\s+(fmi3\w+)TYPE\s+fmi3\w+;", (headers / "fmi3Functions.h").read_text()))
    exported = {name for name, _, _ in functions} | set(unsupported)
    missing = sorted(declared - exported)
    if missing:
        fail(f"fmi3Functions.h declares functions ffi.rs does not export: {', '.join(missing)}")
    unknown = sorted(exported - declared)
    if unknown:
        fail(f"ffi.rs exports functions fmi3Functions.h does not declare: {', '.join(unknown)}")
    for name in unsupported:
        m = re.search(rf"typedef\s+(\w+)\s+{name}TYPE\s*\(\s*(\w+)", header_text)
        if not m or m.group(1) != "fmi3Status" or m.group(2) != "fmi3Instance":
            fail(f"{name}: exported as unsupported (instance in, fmi3Status out) but the header says {m.group(0) if m else 'nothing'}")

    lines = [
        "#include <stdbool.h>",
        "#include <stddef.h>",
        "#include <stdint.h>",
        '#include "fmi3Functions.h"',
        "",
        "/* sizes of the types ffi.rs uses */",
        '_Static_assert(sizeof(fmi3Boolean) == sizeof(bool) && sizeof(bool) == 1, "fmi3Boolean is Rust bool");',
        '_Static_assert(sizeof(fmi3ValueReference) == 4, "fmi3ValueReference is u32");',
        '_Static_assert(sizeof(fmi3Float64) == 8, "fmi3Float64 is f64");',
        '_Static_assert(sizeof(fmi3Status) == sizeof(int), "fmi3Status is a repr(C) enum");',
        '_Static_assert(sizeof(fmi3Instance) == sizeof(void*), "fmi3Instance is *mut c_void");',
        "",
        "/* Status discriminants */",
    ]
    if sorted(v for v, _ in values) != sorted(STATUS):
        fail(f"Status has variants {[v for v, _ in values]}, expected {list(STATUS)}")
    for variant, value in values:
        lines.append(f'_Static_assert({STATUS[variant]} == {value}, "Status::{variant} = {value}");')
    lines.append("")
    lines.append("/* callback types */")
    for name, typedef in callback_types(instance) + callback_types(ffi):
        lines.append(typedef)
        header_name = {
            "LogMessage": "fmi3LogMessageCallback",
            "IntermediateUpdate": "fmi3IntermediateUpdateCallback",
            "ClockUpdate": "fmi3ClockUpdateCallback",
            "Preemption": "fmi3LockPreemptionCallback",
        }.get(name)
        if header_name:
            lines.append(f'_Static_assert(__builtin_types_compatible_p(loam_{name}, {header_name}), "{name} is {header_name}");')
    lines.append("")
    lines.append("/* the implemented functions with their Rust signatures: conflicting types fail */")
    for name, params, ret in functions:
        lines.append(c_prototype(name, params, ret) + ";")
    source = "\n".join(lines) + "\n"

    with tempfile.TemporaryDirectory() as tmp:
        path = pathlib.Path(tmp) / "fmi3_layout_check.c"
        path.write_text(source)
        result = subprocess.run(
            [compiler, "-std=c11", "-fsyntax-only", "-Wall", "-Werror", f"-I{headers}", str(path)],
            capture_output=True,
            text=True,
        )
    if result.returncode != 0:
        print(source, file=sys.stderr)
        fail(f"the C check does not compile against {headers}:\n{result.stderr}")
    print(
        f"check_fmi_header: {len(functions)} implemented functions, {len(unsupported)} unsupported ones, "
        f"Status and the callback types agree with the FMI 3.0 headers of fmpy {fmpy.__version__} ({compiler})"
    )


if __name__ == "__main__":
    main()
