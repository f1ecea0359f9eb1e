"""Surface constructions: a QuadMesh in, a PatchNetwork out."""
