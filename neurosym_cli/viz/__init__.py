"""Pictures of whom agents talk to (paper figures 1, 3, 4 and 5): rollout animations and static episode plots
(``animate.py``), trajectories, attention maps and a program's rule regions (``figures.py``), drawn from
recorded episodes (``episode.py``) and the DSL's own evaluator; shared drawing helpers in ``draw.py``."""
