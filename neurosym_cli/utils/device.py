"""Device resolution: ``auto`` picks a GPU when one is present; everything runs on CPU."""

from __future__ import annotations

import torch

from ..config import ConfigError


def resolve_device(name: str) -> torch.device:
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if name.startswith("cuda") and not torch.cuda.is_available():
        raise ConfigError(f"device={name} asked for, but no CUDA GPU is available; use device=auto or device=cpu")
    return torch.device(name)
