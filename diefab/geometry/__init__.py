"""Convex polyhedra, closed meshes, their symmetries, spanning trees and plane layouts: pure geometry."""
