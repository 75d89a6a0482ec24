"""Search evaluation: a query set with ground truth from the synthetic world, and RefAV's scenario-mining metrics."""
