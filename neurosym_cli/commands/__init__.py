"""One module per verb; the only layer that sees Hydra's DictConfig."""
