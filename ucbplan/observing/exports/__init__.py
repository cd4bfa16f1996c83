"""Observatory and proposal exports of the blocks table, one function per format."""
