// Generated meshes for tests: every family the codec must round-trip, without
// needing the corpus. All are deterministic (seeded).
#pragma once
#include <cstdint>
#include <vector>

#include "tsm/mesh.hpp"

namespace tsm_test {

// Icosahedron subdivided `level` times, on the unit sphere (closed, genus 0).
tsm::Mesh icosphere(int level);
// Closed surface of genus g (g >= 0): the boundary of a slab with g square
// through-holes, each voxel split into `res`^3 sub-voxels, quads split in two.
tsm::Mesh genus_surface(int g, int res = 2);
// n x n vertex grid in the plane, triangulated; with `holes` square holes
// (faces removed) spread over it. Open surface with 1 + holes boundary loops.
tsm::Mesh grid_with_holes(int n, int holes);
// A triangle fan of n triangles around one vertex (open or closed disk).
tsm::Mesh fan(int n, bool closed);
// A triangle strip of n triangles.
tsm::Mesh strip(int n);
// A Moebius strip of n quads (2n triangles): non-orientable.
tsm::Mesh moebius(int n);
// k triangles sharing one edge (k >= 2): a non-manifold edge when k > 2.
tsm::Mesh book(int k);
// Two fans sharing only their apex: a bowtie (non-manifold vertex).
tsm::Mesh bowtie();
// An icosphere with one face flipped: inconsistent orientation.
tsm::Mesh flipped_face_sphere(int level);
// Random triangle soup: `faces` triangles over `vertices` random points, some
// degenerate and duplicate faces, some unreferenced vertices.
tsm::Mesh random_soup(int vertices, int faces, uint32_t seed);
// A closed cube of 6 quads; and a single n-gon.
tsm::Mesh cube_quads();
tsm::Mesh ngon(int n);
// Disjoint copies of `m`, each shifted along x.
tsm::Mesh copies(const tsm::Mesh& m, int count);
// `m` (triangles) with every face also given reversed on the same vertices,
// after all of them: double-sided, as exporters write thin geometry.
tsm::Mesh double_sided(tsm::Mesh m);
// `m` with every coordinate moved by a uniform random offset in
// [-amplitude, amplitude] (std::mt19937 seeded with `seed`): a noisy surface.
tsm::Mesh jittered(tsm::Mesh m, float amplitude, uint32_t seed);

// n x n vertices, each quad split along a random diagonal, every 7th quad
// left out (holes) and a fin of three faces on every 11th quad's lower edge
// (stitches): irregular runs, as on a scan (the fast levels' run tables).
tsm::Mesh irregular_grid(int n, uint32_t seed);

// Every face gets vertices of its own carrying its normal (flat shading,
// glTF style).
tsm::Mesh flat_shaded(const tsm::Mesh& in);
// icosphere(level) flat-shaded as a glTF exporter writes it: a vertex per
// corner, a `normal` vertex attribute (the face's), and a `texcoord` vertex
// attribute (spherical, from the position: equal on the split vertices of one
// point, so each point has one texture wedge and a normal wedge per face).
tsm::Mesh flat_shaded_textured_sphere(int level);

// An open cylinder as an OBJ exporter writes it: one vertex per position, a
// `texcoord` corner attribute whose list has one value per (ring, column),
// the seam's column twice (u = 0 and u = 1), the corners naming them.
tsm::Mesh indexed_uv_cylinder(int around, int rings);

// icosphere(level) flat-shaded as an OBJ exporter writes it: one vertex per
// position, a `normal` corner attribute with one value per face (a vn list),
// each corner naming its face's.
tsm::Mesh indexed_flat_sphere(int level);

}  // namespace tsm_test
