"""The pose library: a grid of reach targets solved in worker processes, with a resumable index."""
