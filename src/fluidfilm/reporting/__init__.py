"""Reports rendered from the pipeline's outputs: the README's and docs' generated blocks, the paper comparison."""
