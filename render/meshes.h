// Internal to armsim_render: tessellated unit shapes the renderer draws with vertex arrays.
// Pure geometry (no GL); every mesh is interleaved normal+position floats (GL_N3F_V3F layout).
#pragma once

#include "muscles/simbody.h"

#include <vector>

namespace armsim::render_detail {

/// A triangle or quad list; each vertex is 6 floats: normal (x, y, z) then position (x, y, z).
struct TriMesh {
    enum Mode { Triangles, Quads };
    Mode mode = Triangles;
    std::vector<float> data;
    int getNumVertices() const { return int(data.size() / 6); }
    void add(const SimTK::Vec3& normal, const SimTK::Vec3& position);
};

/// Tessellation level (>= 1) for a DecorativeGeometry resolution (<= 0 means default, level 2),
/// following Simbody's visualizer: level = max(1, floor(2*resolution)), capped at 8.
int calcTessellationLevel(double resolution);

/// Unit sphere (radius 1, centre at origin), 16*level slices around y and 8*level stacks.
TriMesh makeSphere(int level);
/// Cylinder of radius 1 along y from y=-1 to y=1 with both caps (Simbody's cylinder axis is y).
TriMesh makeCylinder(int level);
/// Cone with base radius 1 at y=0 and apex at y=1, base closed.
TriMesh makeCone(int level);
/// Cube [-1, 1]^3 as six quads (wireframe shows the 12 edges only).
TriMesh makeBrick();
/// Disk of radius 1 in the x-y plane, normal +z.
TriMesh makeDisk(int level);
/// Torus about z: tube centre circle radius torusRadius, tube radius tubeRadius.
TriMesh makeTorus(double torusRadius, double tubeRadius, int level);
/// A SimTK::PolygonalMesh with flat shading; faces with more than three vertices are fanned.
TriMesh makeFromPolygonalMesh(const SimTK::PolygonalMesh& mesh);

}  // namespace armsim::render_detail
