"""What a scheme module imports (docs/extending.md, section 6): the base classes of a communication scheme and of its
provider. A scheme outside the package is found by the entry-point group ``neurosym.schemes`` or by
``baseline._target_=package.module.Class`` (neurosym_cli/schemes/registry.py)."""

from neurosym_cli.baselines import Artifact, BaselineConfig, Stage
from neurosym_cli.policy.protocol import CommBase, CommWrapper, unwrap
from neurosym_cli.schemes.families import OnOracle, OwnModel, OwnRule

__all__ = ["Artifact", "BaselineConfig", "CommBase", "CommWrapper", "OnOracle", "OwnModel", "OwnRule", "Stage",
           "unwrap"]
