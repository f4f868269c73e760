"""neurosym: neurosymbolic transformers for multi-agent communication (NeurIPS 2020), as a CLI.

Packages are cut by concept. Import layers, lowest first: a module imports from its own layer and the layers
below it, never from above (tests/test_layers.py reads this table and checks every import, lazy ones included):

    layer 0: errors verb_config config baselines utils stats defaults degrees  errors, schemas, what a baseline
                                                 is (its interface), statistics, the console
                                                 script's persistent task and budget, the words for degrees
    layer 1: dsl tasks                           the program language; the task boundary and the paper's tasks
    layer 2: policy                              the transformer and the communication providers
    layer 3: step rollout episode viz            one environment step; one batched rollout; a recorded episode;
                                                 pictures
    layer 4: training evaluation synth schemes run plotting overrides choices seeds export  the
                                                 training loop; the
                                                 evaluation protocol; program search; the baselines' registry;
                                                 the run directory (artifact names, checkpoints, the models a
                                                 baseline runs on, remake commands); figures;
                                                 override checks; the choices of config groups and
                                                 launchers; results across training seeds; artifacts that
                                                 run without neurosym
    layer 5: stages                              what each verb does to a run directory; the stage graph
    layer 6: commands                            the Hydra verbs (the only layer that sees Hydra)
    layer 7: cli argv helptext api               the console script, its reading of the command line and its
                                                 help per command; the Python API (neurosym.api)
"""

__version__ = "0.1.0"

from .utils import cpu as _cpu  # noqa: E402  (stdlib only)

# pin the CPU kernels before anything imports torch (NEUROSYM_CPU_KERNELS, default avx2); not final: the console
# script reads its command line next, and a command its config
_cpu.warn_once(final=False)
