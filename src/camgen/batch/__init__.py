"""Datasets: a dataset spec expanded into many Jobs, run by a local process pool, resumably."""
