"""Files in and out: checkpoints, results.h5, VTK series, CSV tables, paths, LIGGGHTS decks."""
