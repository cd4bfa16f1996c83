"""At the telescope: the night chart, the night sheet (HTML) and the live countdown."""
