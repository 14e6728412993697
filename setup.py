"""The package's one compiled extension, the neurons' normals (skinhil/model/normals/_kernel.c);
everything else is declared in pyproject.toml."""

from __future__ import annotations

import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

_NEEDS = ("skinhil needs a C compiler and the Python headers to build its normals kernel: "
          "install gcc or clang and the Python development headers "
          "(e.g. apt-get install gcc python3-dev), then run pip install again")


class BuildExt(build_ext):
    """build_ext that ends a failed compile with one line saying what to install."""

    def run(self) -> None:
        try:
            super().run()
        except Exception as exc:  # distutils' CompileError, PlatformError, missing tools
            sys.stderr.write(f"error: {_NEEDS} ({type(exc).__name__}: {exc})\n")
            raise SystemExit(1) from None

    def build_extension(self, ext: Extension) -> None:
        try:
            super().build_extension(ext)
        except Exception as exc:
            sys.stderr.write(f"error: {_NEEDS} ({type(exc).__name__}: {exc})\n")
            raise SystemExit(1) from None


# -ffp-contract=off: the compiler fuses no multiply-add the source does not name, so every
# path does the same float operations (the kernel's header comment)
NORMALS = Extension("skinhil.model.normals._kernel",
                    sources=["skinhil/model/normals/_kernel.c"],
                    extra_compile_args=["-O2", "-ffp-contract=off", "-fno-fast-math"])

setup(ext_modules=[NORMALS], cmdclass={"build_ext": BuildExt})
