"""Builds the Python package hapsyn with setuptools by running the project's CMake.

`pip install .` (pyproject.toml: build backend setuptools.build_meta) runs build_ext below,
which configures the whole CMake project (-DHAPSYN_WITH_PYTHON=ON -DHAPSYN_BUILD_TESTS=OFF,
Release), builds it, installs it with `cmake --install` into a staging prefix and copies the
runtime part into the wheel's package directory:

    hapsyn/__init__.py, __init__.pyi, py.typed    (also copied by setuptools' build_py)
    hapsyn/_hapsyn.cpython-*.so                    RPATH $ORIGIN/lib
    hapsyn/lib/libhapsyn.so.<major>.<minor>        the file the soname names (no symlinks)
    hapsyn/lib/hapsyn/plugins/hapsyn-*.so          found by the registry next to libhapsyn
    hapsyn/share/hapsyn/...                        share/ data files and problems/

Left out of the wheel: headers, the CMake package files, the hapsyn program and libhapsyn's
other two names (a wheel cannot hold symlinks: each would be a second and third copy of the
library). Those come with `cmake --install` (python/README.md).

Environment:
    HAPSYN_PIP_BUILD_DIR        the CMake build directory, kept between installs so that a
                                second `pip install .` only rebuilds what changed
                                (default: build/pip-wheel under the source tree)
    CMAKE_BUILD_PARALLEL_LEVEL  compile jobs (default: the number of CPUs)
    CMAKE_GENERATOR             the generator of a new build directory (default: Ninja when
                                ninja is on PATH, else CMake's default)
    HAPSYN_CMAKE_ARGS           more arguments for the configure step, split like a shell
                                (e.g. "-DHAPSYN_WITH_MPI=OFF")
"""
import os
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext
from setuptools.command.sdist import sdist

try:
    from setuptools.errors import ExecError, SetupError
except ImportError:  # setuptools < 59
    from distutils.errors import DistutilsExecError as ExecError, DistutilsSetupError as SetupError

SOURCE_DIR = Path(__file__).resolve().parent


def _build_dir() -> Path:
    configured = os.environ.get("HAPSYN_PIP_BUILD_DIR", "").strip()
    path = Path(configured).expanduser() if configured else SOURCE_DIR / "build" / "pip-wheel"
    return path.resolve()


def _cache_value(cache: Path, key: str) -> str:
    """A value of CMakeCache.txt ("" when absent)."""
    try:
        for line in cache.read_text(errors="replace").splitlines():
            if line.startswith(key + ":"):
                return line.split("=", 1)[1] if "=" in line else ""
    except OSError:
        pass
    return ""


def _run(step: str, command, build_dir: Path) -> None:
    """Runs a CMake step with its output going straight to ours (pip shows it on failure)."""
    print("hapsyn: " + " ".join(shlex.quote(str(c)) for c in command), flush=True)
    sys.stderr.flush()
    try:
        result = subprocess.run([str(c) for c in command], cwd=str(SOURCE_DIR))
    except OSError as error:
        raise ExecError(f"hapsyn: cannot run {command[0]}: {error}") from None
    if result.returncode != 0:
        hint = ""
        if step == "configure":
            hint = ("; the C++ dependencies must be installed first (Debian: bash scripts/setup.sh "
                    "installs Eigen, Boost, pagmo, nlohmann_json, CLI11, pybind11)")
        raise ExecError(f"hapsyn: CMake {step} failed (exit status {result.returncode}) in {build_dir}: "
                        f"CMake's messages are above{hint}")


class CMakeBuild(build_ext):
    """build_ext for the one extension hapsyn._hapsyn: the project's CMake does all of it."""

    def run(self):
        if self.inplace or getattr(self, "editable_mode", False):
            raise SetupError("hapsyn: editable installs are not supported; build with CMake and use "
                             "PYTHONPATH=build/python (python/README.md)")
        cmake = shutil.which(os.environ.get("CMAKE", "cmake"))
        if cmake is None:
            raise SetupError("hapsyn: cmake not found on PATH (Debian: apt-get install cmake)")
        build_dir = _build_dir()
        build_dir.mkdir(parents=True, exist_ok=True)
        stage = build_dir / "install"
        cache = build_dir / "CMakeCache.txt"

        # A build directory made for another source tree (e.g. a moved checkout, or a wheel built
        # from an unpacked sdist with the same HAPSYN_PIP_BUILD_DIR) cannot be reconfigured by
        # CMake: start its cache afresh (the objects are rebuilt).
        cached_source = _cache_value(cache, "CMAKE_HOME_DIRECTORY")
        if cached_source and Path(cached_source).resolve() != SOURCE_DIR:
            print(f"hapsyn: {build_dir} was configured for {cached_source}; configuring it afresh for {SOURCE_DIR}",
                  flush=True)
            cache.unlink()
            shutil.rmtree(build_dir / "CMakeFiles", ignore_errors=True)

        configure = [cmake, "-S", SOURCE_DIR, "-B", build_dir]
        if not cache.exists() and not os.environ.get("CMAKE_GENERATOR") and shutil.which("ninja"):
            configure += ["-G", "Ninja"]
        configure += [
            "-DCMAKE_BUILD_TYPE=Release",
            "-DHAPSYN_WITH_PYTHON=ON",
            "-DHAPSYN_BUILD_TESTS=OFF",
            # The interpreter running this build is the one the module is for.
            f"-DPython3_EXECUTABLE={sys.executable}",
            # Installed into the staging prefix as the package directory itself: the Python files
            # go to <prefix>/../hapsyn = <prefix>, libhapsyn to <prefix>/lib (the module's RPATH is
            # $ORIGIN/lib), the plugins to <prefix>/lib/hapsyn/plugins.
            f"-DCMAKE_INSTALL_PREFIX={stage / 'hapsyn'}",
            "-DCMAKE_INSTALL_LIBDIR=lib",
            "-DHAPSYN_PYTHON_INSTALL_DIR=..",
        ]
        configure += shlex.split(os.environ.get("HAPSYN_CMAKE_ARGS", ""))
        _run("configure", configure, build_dir)

        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", "").strip() or str(os.cpu_count() or 1)
        _run("build", [cmake, "--build", build_dir, "--config", "Release", "--parallel", jobs], build_dir)
        _run("install", [cmake, "--install", build_dir, "--config", "Release"], build_dir)

        self._outputs = self._copy_runtime(stage / "hapsyn", Path(self.build_lib) / "hapsyn")

    def _copy_runtime(self, prefix: Path, package: Path):
        """Copies what `import hapsyn` needs from the install prefix into the wheel's package."""
        modules = sorted(prefix.glob("_hapsyn*.so"))
        lib = prefix / "lib"
        # libhapsyn: one regular file under the name the module and the plugins load (the soname
        # link, whose target is the real file; the development name links to the soname link).
        names = sorted(lib.glob("libhapsyn.so*"))
        libraries = [p for p in names if p.is_symlink() and (lib / os.readlink(p)).is_file()
                     and not (lib / os.readlink(p)).is_symlink()]
        libraries = libraries or [p for p in names if p.is_file() and not p.is_symlink()]
        if not modules or not (lib / "hapsyn" / "plugins").is_dir() or not libraries:
            raise ExecError(f"hapsyn: `cmake --install` left no _hapsyn module, libhapsyn soname or plugins in {prefix}")

        # Replace what an earlier build put here (a removed plugin must not linger in the wheel).
        for old in list(package.glob("_hapsyn*.so")):
            old.unlink()
        for folder in ("lib", "share"):
            shutil.rmtree(package / folder, ignore_errors=True)
        package.mkdir(parents=True, exist_ok=True)

        outputs = []

        def copy(source: Path, target: Path):
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, target, follow_symlinks=True)
            outputs.append(str(target))

        for f in ("__init__.py", "__init__.pyi", "py.typed"):
            if (prefix / f).is_file():
                copy(prefix / f, package / f)
        for module in modules:
            copy(module, package / module.name)
        for library in libraries:
            copy(library, package / "lib" / library.name)
        for folder in (lib / "hapsyn" / "plugins", prefix / "share" / "hapsyn"):
            for source in sorted(folder.rglob("*")):
                if source.is_file():
                    copy(source, package / source.relative_to(prefix))
        return outputs

    def get_outputs(self):
        return list(getattr(self, "_outputs", [])) or super().get_outputs()


class SourceDist(sdist):
    """An sdist that holds the CMake project, so that a wheel can be built from it (build/,
    results/, tests/, docs/ and benchmarks/ are left out: a wheel build needs none of them)."""

    PARTS = ("CMakeLists.txt", "README.md", "cmake", "framework", "plugins", "python", "problems", "share", "examples")

    def make_release_tree(self, base_dir, files):
        extra = []
        for part in self.PARTS:
            path = SOURCE_DIR / part
            found = [path] if path.is_file() else sorted(p for p in path.rglob("*") if p.is_file())
            extra += [str(p.relative_to(SOURCE_DIR)) for p in found
                      if "__pycache__" not in p.parts and not p.name.endswith((".pyc", ".egg-info"))]
        super().make_release_tree(base_dir, sorted(set(files) | set(extra)))


def _setuptools_build_base() -> str:
    # setuptools' own build/ and egg-info go into the CMake build directory, not the source tree
    # (whose build/ may be a CMake build tree of its own).
    base = _build_dir() / "setuptools"
    base.mkdir(parents=True, exist_ok=True)
    return str(base)


setup(
    # The pure-Python files (setup() rather than pyproject.toml's [tool.setuptools], which
    # setuptools 66 still calls beta and warns about).
    packages=["hapsyn"],
    package_dir={"": "python"},
    package_data={"hapsyn": ["__init__.pyi", "py.typed"]},
    include_package_data=False,
    ext_modules=[Extension("hapsyn._hapsyn", sources=[])],
    cmdclass={"build_ext": CMakeBuild, "sdist": SourceDist},
    options={
        "build": {"build_base": _setuptools_build_base()},
        "egg_info": {"egg_base": _setuptools_build_base()},
    },
)
