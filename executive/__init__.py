"""executive: an onboard behaviour-tree mission executive for uncrewed vehicles."""

__version__ = "0.1.0"
