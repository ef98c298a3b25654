"""twin: a digital twin of robot workcells."""
