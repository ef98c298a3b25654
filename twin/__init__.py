"""twin: a digital twin of robot workcells."""

__version__ = "0.1.0"
