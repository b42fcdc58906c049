"""Numerical tolerances, in one place.

Model units are the paper's (the gem's girdle spans z in [-1, 1]); lengths
below are in those units unless the name says otherwise.
"""

#: Largest distance of a face vertex from the face's best-fit plane.
PLANARITY = 1e-9
#: How far outside a face plane another vertex may lie and still count as convex.
CONVEXITY = 1e-9
#: Two unit normals closer than this (1 - cos) are taken as the same plane
#: when coplanar triangles of a mesh are merged.
COPLANAR = 1e-7
#: Smallest stability margin, relative to the die's size, of a face the die can rest on
#: (a face with a smaller margin is transitional).
REST_MARGIN = 1e-9
#: Tilt (radians) of the first step of a die tipping off a transitional face.
TIP = 1e-6
#: Relative distance within which the faces of an inset polyhedron are merged.
INSET_MERGE = 1e-7
#: Smallest face area, edge length and volume that are not degenerate.
AREA = 1e-12
LENGTH = 1e-9
VOLUME = 1e-12
#: Sine of the angle below which three consecutive hull points are collinear.
COLLINEAR = 1e-9
#: Two face/up-direction cosines closer than this are a tie.
TIE = 1e-9
#: Relative difference in area or volume between a mesh and its convex hull
#: below which the mesh counts as convex.
MESH_REL = 1e-6
#: Largest relative difference between an STL's volume and uncut volume ∓ text area × depth.
STL_VOLUME_REL = 0.005
#: Paper nets (mm): two flat polygons overlapping by no more than this along
#: some axis only touch (shared fold edges, tab bases, vertices).
NET_OVERLAP_MM = 1e-6
#: A map carrying every vertex within this fraction of the die's radius of a vertex is a symmetry.
SYMMETRY_REL = 1e-6
#: Paper nets (mm): a tab layout whose tabs' centre of mass lies this close to the die's
#: symmetry axis (or plane, or centre) counts as symmetric; among those the smallest wins.
NET_TAB_OFFSET_MM = 0.01

#: Probabilities summing to 1 within this are a distribution.
PROBABILITY_SUM = 1e-6
