"""The transformer policy and the communication providers that decide whom it hears.

Its names load on first use: ``policy.protocol`` (what the schemes inherit when registered) imports no torch."""

from importlib import import_module

_WHERE = {"CommContext": "comm", "FullComm": "comm", "NearestComm": "comm", "NoComm": "comm", "TopKComm": "comm",
          "CommBase": "protocol", "CommProvider": "protocol", "unwrap": "protocol",
          "CommTransformer": "transformer", "PolicyOutput": "transformer"}

__all__ = sorted(_WHERE)


def __getattr__(name: str):
    if name not in _WHERE:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(import_module(f".{_WHERE[name]}", __name__), name)
