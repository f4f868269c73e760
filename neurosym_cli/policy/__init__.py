"""The transformer policy and the communication providers that decide whom it hears."""

from .comm import CommContext, CommProvider, FullComm, NearestComm, NoComm, TopKComm
from .transformer import CommTransformer, PolicyOutput

__all__ = ["CommContext", "CommProvider", "CommTransformer", "FullComm", "NearestComm", "NoComm", "PolicyOutput",
           "TopKComm"]
