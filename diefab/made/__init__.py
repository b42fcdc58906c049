"""The die as it is made: what fabrication adds to the ideal polyhedron (markers, labels, tabs)."""
