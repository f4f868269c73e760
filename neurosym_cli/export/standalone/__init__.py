"""Files copied verbatim into every export folder. They import nothing of neurosym (the standard library, numpy,
and onnxruntime or torch where present), so a robot, or `neurosym export --check`'s isolated process, runs them."""
