"""neurosym: neurosymbolic transformers for multi-agent communication (NeurIPS 2020), as a CLI."""

__version__ = "0.1.0"
