"""File input and output: mesh files, patch files, network files; every write is atomic."""
