"""Writers and readers at the edge of the pipeline."""
