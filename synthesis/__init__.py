"""agrisynth: design rules of transplanting and harvesting machines as CasADi/IPOPT programs."""

__version__ = "0.1.0"
