"""numba's kernel cache configuration: defined once in :mod:`protocols.kernel_cache` (the
wire codecs, which compile kernels, stand alone), re-exported here for the model."""

from __future__ import annotations

from protocols.kernel_cache import (
    CACHE_DIR,
    KEEP_VERSIONS,
    KERNEL_PACKAGES,
    cache_base,
    configure,
    source_files,
    source_hash,
)

__all__ = ["CACHE_DIR", "KEEP_VERSIONS", "KERNEL_PACKAGES", "cache_base", "configure",
           "source_files", "source_hash"]
