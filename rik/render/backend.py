"""Choosing Mitsuba 3's variant: ``cuda_ad_rgb`` on an NVIDIA GPU, ``llvm_ad_rgb`` on the CPU when a working
LLVM (16 or newer) is installed, ``scalar_rgb`` otherwise.

Dr.Jit loads whatever ``libLLVM`` it finds first. On Debian that is Mesa's LLVM 15, which aborts the process
(``LLVM ERROR: Cannot select ... fminimum``) instead of raising, so the choice cannot be made by trying: rik
looks for a library of version 16 or newer and points ``DRJIT_LIBLLVM_PATH`` at it before Mitsuba is imported.
``scripts/setup.sh`` installs Debian's ``libllvm19``.
"""

from __future__ import annotations

import glob
import os
import re

from rik.errors import RikError

VARIANTS = ("cuda_ad_rgb", "llvm_ad_rgb", "scalar_rgb")
"""The variants rik renders with, fastest first."""
MIN_LLVM = 16
LLVM_SEARCH = ("/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu", "/usr/lib64", "/usr/lib",
               "/usr/local/lib", "/opt/homebrew/opt/llvm/lib", "/usr/local/opt/llvm/lib")


def llvm_library() -> str | None:
    """Path of the newest ``libLLVM`` of version 16 or newer (``DRJIT_LIBLLVM_PATH`` when set), or None."""
    given = os.environ.get("DRJIT_LIBLLVM_PATH")
    if given:
        return given if os.path.exists(given) else None
    found: list[tuple[int, str]] = []
    for folder in LLVM_SEARCH:
        for path in glob.glob(os.path.join(folder, "libLLVM*.so*")) + glob.glob(os.path.join(folder, "libLLVM*.dylib")):
            match = re.search(r"libLLVM[-.]?(\d+)", os.path.basename(path))
            if match and int(match.group(1)) >= MIN_LLVM:
                found.append((int(match.group(1)), path))
    return max(found)[1] if found else None


def _cuda_present() -> bool:
    return any(os.path.exists(p) for p in ("/dev/nvidia0", "/dev/nvidiactl")) or bool(glob.glob("/dev/nvidia[0-9]*"))


def available_variants() -> list[str]:
    """The variants this machine can render with, fastest first (``scalar_rgb`` always)."""
    out = []
    if _cuda_present():
        out.append("cuda_ad_rgb")
    if llvm_library():
        out.append("llvm_ad_rgb")
    return [*out, "scalar_rgb"]


def _activate(variant: str) -> str:
    if variant == "llvm_ad_rgb":
        os.environ.setdefault("DRJIT_LIBLLVM_PATH", llvm_library() or "")
    import mitsuba as mi

    try:
        mi.set_variant(variant)
    except Exception as exc:  # Dr.Jit raises when the backend's library or device is missing
        raise RikError(f"Mitsuba variant {variant} does not work on this machine: {str(exc).splitlines()[0]}") from None
    return variant


def use_variant(requested: str = "auto") -> str:
    """Activate Mitsuba's ``requested`` variant (``auto``: the fastest that works here) and return its name.

    Raises a :class:`RikError` for a name rik does not render with, or a backend this machine lacks."""
    if requested != "auto" and requested not in VARIANTS:
        raise RikError(f"renderer variant '{requested}' is not supported; use one of: auto, {', '.join(VARIANTS)}")
    here = available_variants()
    if requested == "auto":
        last: RikError | None = None
        for variant in here:
            try:
                return _activate(variant)
            except RikError as exc:
                last = exc
        raise last or RikError("no Mitsuba variant works on this machine")
    if requested not in here:
        why = {"cuda_ad_rgb": "no NVIDIA GPU found",
               "llvm_ad_rgb": f"no libLLVM {MIN_LLVM} or newer found (install Debian's libllvm19, or set "
                              "DRJIT_LIBLLVM_PATH)"}[requested]
        raise RikError(f"renderer variant '{requested}' is not available here: {why}; available: {', '.join(here)}")
    return _activate(requested)
