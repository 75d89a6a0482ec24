"""Multi-agent motion: the ``MotionPredictor`` protocol, the reactive traffic model and refinement."""
