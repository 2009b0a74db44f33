#include "render/meshes.h"

#include "basics/angles.h"

#include <algorithm>
#include <cmath>

namespace armsim::render_detail {

using SimTK::Vec3;

void TriMesh::add(const Vec3& normal, const Vec3& position) {
    for (int i = 0; i < 3; ++i) data.push_back(float(normal[i]));
    for (int i = 0; i < 3; ++i) data.push_back(float(position[i]));
}

int calcTessellationLevel(double resolution) {
    if (!(resolution > 0)) return 2;
    return std::clamp(int(2 * resolution), 1, 8);
}

namespace {

Vec3 spherePoint(double theta, double phi) {
    // theta: angle from +y (0..pi); phi: azimuth about y.
    return {std::sin(theta) * std::cos(phi), std::cos(theta), -std::sin(theta) * std::sin(phi)};
}

void addTriangle(TriMesh& m, const Vec3& n0, const Vec3& p0, const Vec3& n1, const Vec3& p1,
                 const Vec3& n2, const Vec3& p2) {
    m.add(n0, p0);
    m.add(n1, p1);
    m.add(n2, p2);
}

}  // namespace

TriMesh makeSphere(int level) {
    TriMesh m;
    const int slices = 16 * level, stacks = 8 * level;
    for (int i = 0; i < stacks; ++i) {
        const double t0 = kPi * i / stacks, t1 = kPi * (i + 1) / stacks;
        for (int j = 0; j < slices; ++j) {
            const double f0 = 2 * kPi * j / slices, f1 = 2 * kPi * (j + 1) / slices;
            const Vec3 a = spherePoint(t0, f0), b = spherePoint(t1, f0), c = spherePoint(t1, f1),
                       d = spherePoint(t0, f1);
            if (i > 0) addTriangle(m, a, a, b, b, d, d);
            if (i < stacks - 1) addTriangle(m, b, b, c, c, d, d);
        }
    }
    return m;
}

TriMesh makeCylinder(int level) {
    TriMesh m;
    const int slices = 16 * level;
    const Vec3 up(0, 1, 0), down(0, -1, 0);
    for (int j = 0; j < slices; ++j) {
        const double f0 = 2 * kPi * j / slices, f1 = 2 * kPi * (j + 1) / slices;
        const Vec3 n0(std::cos(f0), 0, -std::sin(f0)), n1(std::cos(f1), 0, -std::sin(f1));
        const Vec3 b0 = n0 + down, t0 = n0 + up, b1 = n1 + down, t1 = n1 + up;
        addTriangle(m, n0, b0, n1, b1, n1, t1);
        addTriangle(m, n0, b0, n1, t1, n0, t0);
        addTriangle(m, up, up, up, t0, up, t1);
        addTriangle(m, down, down, down, b1, down, b0);
    }
    return m;
}

TriMesh makeCone(int level) {
    TriMesh m;
    const int slices = 16 * level;
    const Vec3 apex(0, 1, 0), down(0, -1, 0), centre(0, 0, 0);
    for (int j = 0; j < slices; ++j) {
        const double f0 = 2 * kPi * j / slices, f1 = 2 * kPi * (j + 1) / slices;
        const double fm = 0.5 * (f0 + f1);
        const Vec3 r0(std::cos(f0), 0, -std::sin(f0)), r1(std::cos(f1), 0, -std::sin(f1));
        // Side normal of a cone with unit radius and height: (radial + y)/sqrt(2).
        const Vec3 n0 = (r0 + Vec3(0, 1, 0)) / std::sqrt(2.0), n1 = (r1 + Vec3(0, 1, 0)) / std::sqrt(2.0);
        const Vec3 nm = (Vec3(std::cos(fm), 0, -std::sin(fm)) + Vec3(0, 1, 0)) / std::sqrt(2.0);
        addTriangle(m, n0, r0, n1, r1, nm, apex);
        addTriangle(m, down, centre, down, r1, down, r0);
    }
    return m;
}

TriMesh makeBrick() {
    TriMesh m;
    m.mode = TriMesh::Quads;
    for (int axis = 0; axis < 3; ++axis) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        for (int sign : {-1, 1}) {
            Vec3 n(0);
            n[axis] = sign;
            const double su[4] = {-1, 1, 1, -1}, sv[4] = {-1, -1, 1, 1};
            for (int k = 0; k < 4; ++k) {
                const int kk = sign > 0 ? k : 3 - k;  // counter-clockwise seen from outside
                Vec3 p = n;
                p[u] = su[kk];
                p[v] = sv[kk];
                m.add(n, p);
            }
        }
    }
    return m;
}

TriMesh makeDisk(int level) {
    TriMesh m;
    const int slices = 16 * level;
    const Vec3 n(0, 0, 1), centre(0);
    for (int j = 0; j < slices; ++j) {
        const double f0 = 2 * kPi * j / slices, f1 = 2 * kPi * (j + 1) / slices;
        addTriangle(m, n, centre, n, Vec3(std::cos(f0), std::sin(f0), 0), n,
                    Vec3(std::cos(f1), std::sin(f1), 0));
    }
    return m;
}

TriMesh makeTorus(double torusRadius, double tubeRadius, int level) {
    TriMesh m;
    const int slices = 18 * level, sides = 8 * level;
    auto point = [&](int i, int j, Vec3& normal) {
        const double u = 2 * kPi * i / slices, v = 2 * kPi * j / sides;
        const Vec3 radial(std::cos(u), std::sin(u), 0);
        normal = std::cos(v) * radial + std::sin(v) * Vec3(0, 0, 1);
        return torusRadius * radial + tubeRadius * normal;
    };
    for (int i = 0; i < slices; ++i)
        for (int j = 0; j < sides; ++j) {
            Vec3 na, nb, nc, nd;
            const Vec3 a = point(i, j, na), b = point(i + 1, j, nb), c = point(i + 1, j + 1, nc),
                       d = point(i, j + 1, nd);
            addTriangle(m, na, a, nb, b, nc, c);
            addTriangle(m, na, a, nc, c, nd, d);
        }
    return m;
}

TriMesh makeFromPolygonalMesh(const SimTK::PolygonalMesh& mesh) {
    TriMesh m;
    for (int f = 0; f < mesh.getNumFaces(); ++f) {
        const int n = mesh.getNumVerticesForFace(f);
        if (n < 3) continue;
        const Vec3& p0 = mesh.getVertexPosition(mesh.getFaceVertex(f, 0));
        for (int k = 1; k + 1 < n; ++k) {
            const Vec3& p1 = mesh.getVertexPosition(mesh.getFaceVertex(f, k));
            const Vec3& p2 = mesh.getVertexPosition(mesh.getFaceVertex(f, k + 1));
            Vec3 normal = SimTK::cross(p1 - p0, p2 - p0);
            const double len = normal.norm();
            if (len <= 0) continue;
            normal /= len;
            addTriangle(m, normal, p0, normal, p1, normal, p2);
        }
    }
    return m;
}

}  // namespace armsim::render_detail
