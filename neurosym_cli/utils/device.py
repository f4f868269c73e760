"""Device resolution: ``auto`` picks a GPU when one is present; everything runs on CPU."""

from __future__ import annotations

import torch

from ..config import ConfigError


def resolve_device(name: str) -> torch.device:
    """``auto`` -> a GPU when present, else the CPU; a named GPU that is missing is a one-line ConfigError. On a GPU
    TF32 is off (issue 39): float32 matmuls in full precision, as on the CPU, so 200 steps of backpropagation do
    not amplify TF32's 10-bit mantissa into other results."""
    if name == "auto":
        name = "cuda" if torch.cuda.is_available() else "cpu"
    if name.startswith("cuda") and not torch.cuda.is_available():
        raise ConfigError(f"device={name} asked for, but no CUDA GPU is available; use device=auto or device=cpu")
    if name.startswith("cuda"):
        full_precision()
    return torch.device(name)


def full_precision() -> None:
    """float32 matmuls and convolutions without TF32 (torch's matmul default, made explicit; cuDNN's is TF32)."""
    torch.set_float32_matmul_precision("highest")
    torch.backends.cudnn.allow_tf32 = False
