"""`neurosym export`: a run's program and policy as artifacts that need no neurosym (docs/deploy.md).

    spec.py      the program as JSON: its AST, the features it reads with units and sources, the rule semantics
    codegen.py   the program as a standard-library Python module and as a single-header C99 function
    policy.py    the transformer as functions to export (Graph), whom to hear given as input, the task's target inside
    formats.py   those as files: TorchScript (policy.pt), torch.export (policy.pt2), ONNX (dynamo or legacy exporter)
    golden.py    recorded inputs and outputs of evaluation episodes (golden vectors)
    check.py     replays the golden vectors through every artifact in a process that cannot import neurosym
    readme.py    the README written into each export folder
    standalone/  files copied verbatim into the folder (the checker, a per-agent runtime): no neurosym imports

Nothing here is imported by the other verbs.
"""

SEMANTICS = "neurosym-rules/1"
"""the version of the rule semantics the exported programs implement (spec.SEMANTICS_TEXT says what it is)"""
