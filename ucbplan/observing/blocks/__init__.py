"""The blocks table: blocks planned, their columns, made, formatted, written, read, accounted."""
