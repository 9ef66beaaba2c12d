"""native_build.py: where the package's C library comes from, for setup.py and build_ffi.py.

Inside the cbvh repository (python/ beside configure.ac) the library and the `cbvh` command are built from
the repository's sources by their own autotools build, out of tree in the setuptools build folder
(static, position-independent code, so that it links into the extension). Elsewhere an installed libcbvh
is used through pkg-config (`cbvh.pc`), and cook_file runs the `cbvh` command found on PATH.
"""
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
# The repository: python/'s parent, or $CBVH_SOURCE_DIR for a copy of python/ built elsewhere.
REPOSITORY = os.environ.get("CBVH_SOURCE_DIR") or os.path.dirname(HERE)
NATIVE = os.path.join(HERE, "build", "native")


def from_repository() -> bool:
    return os.path.exists(os.path.join(REPOSITORY, "configure.ac")) and not os.environ.get("CBVH_USE_INSTALLED")


def _run(args, cwd):
    print("cbvh native build:", " ".join(args), file=sys.stderr)
    subprocess.run(args, cwd=cwd, check=True)


def has_assimp() -> bool:
    return shutil.which("pkg-config") is not None and subprocess.run(
        ["pkg-config", "--exists", "assimp"]).returncode == 0


def build() -> None:
    """Configures (once) and builds libcbvh and, with assimp, the cbvh command in NATIVE."""
    if not from_repository():
        return
    if not os.path.exists(os.path.join(REPOSITORY, "configure")):
        _run(["autoreconf", "-fi"], REPOSITORY)
    os.makedirs(NATIVE, exist_ok=True)
    tools = has_assimp()
    if not os.path.exists(os.path.join(NATIVE, "Makefile")):
        _run([os.path.join(REPOSITORY, "configure"), "-q", "--disable-shared", "--with-pic", "--disable-tests",
              "--without-embree", "--without-bullet"] + ([] if tools else ["--disable-tools"]), NATIVE)
    jobs = str(os.cpu_count() or 1)
    _run(["make", "-s", "-j" + jobs, "lib/libcbvh.la"] + (["tools/cbvh"] if tools else []), NATIVE)


def tool_path():
    """The cbvh command built beside the library, or None."""
    path = os.path.join(NATIVE, "tools", "cbvh")
    return path if from_repository() and os.path.exists(path) else None


def compile_args() -> dict:
    """Keyword arguments for cffi's set_source: headers and the library to link."""
    if from_repository():
        return {
            "include_dirs": [os.path.join(REPOSITORY, "include"), os.path.join(NATIVE, "include")],
            "extra_objects": [os.path.join(NATIVE, "lib", ".libs", "libcbvh.a")],
            "libraries": ["z", "m", "pthread"],
        }

    def pkg_config(flag):
        out = subprocess.run(["pkg-config", flag, "cbvh"], check=True, capture_output=True, text=True).stdout
        return out.split()

    try:
        cflags, libs = pkg_config("--cflags"), pkg_config("--libs")
    except (OSError, subprocess.CalledProcessError) as e:
        raise SystemExit("cbvh: outside the cbvh repository the package links an installed libcbvh, "
                         "but pkg-config does not find cbvh.pc: %s" % e)
    library_dirs = [f[2:] for f in libs if f.startswith("-L")]
    return {
        "include_dirs": [f[2:] for f in cflags if f.startswith("-I")],
        "library_dirs": library_dirs,
        "runtime_library_dirs": library_dirs,  # a libcbvh.so outside the loader's paths is still found
        "libraries": [f[2:] for f in libs if f.startswith("-l")],
    }
