"""SIMSplat core algorithms: framework-free (torch, numpy, OpenCV only)."""
