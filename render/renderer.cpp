#include "render/renderer.h"

#include "basics/angles.h"
#include "basics/errors.h"
#include "basics/param_node.h"
#include "render/meshes.h"

#include <fmt/format.h>

#include <GL/osmesa.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>

namespace armsim {

using SimTK::Transform;
using SimTK::Vec3;
using SimTK::Vec4;
using render_detail::TriMesh;

namespace {

constexpr int kMinSize = 16;
constexpr int kMaxSize = 4096;
constexpr int kMaxSupersample = 4;
constexpr int kMaxBufferSide = 8192;
constexpr double kMaxLineThickness = 64;
const Vec3 kDefaultColor(0.7, 0.7, 0.7);       // Simbody's visualizer default (grey)
const Vec3 kDefaultPointColor(1, 0, 1);        // Simbody's visualizer default (magenta)
constexpr double kPointArmLength = 0.05;       // half-length of a DecorativePoint's cross (m)
constexpr double kArrowHeadRadiusRatio = 0.35; // arrow head base radius / tip length

std::string formatVec(const Vec3& v) { return fmt::format("[{:g}, {:g}, {:g}]", v[0], v[1], v[2]); }

void checkEvenSize(const std::string& field, int value) {
    checkField(field, value, Bound::closed(kMinSize, kMaxSize, "px"));
    if (value % 2 != 0)
        throw FieldError(field, "= " + std::to_string(value) + ": expected an even number of pixels");
}

void checkUnitColor(const std::string& field, const Vec3& c) {
    for (int i = 0; i < 3; ++i)
        if (!(c[i] >= 0 && c[i] <= 1))
            throw FieldError(field, "= " + formatVec(c) + ": expected each of r, g, b in [0, 1]");
}

void checkFiniteVec(const std::string& field, const Vec3& v) {
    for (int i = 0; i < 3; ++i)
        if (!std::isfinite(v[i])) throw FieldError(field, "= " + formatVec(v) + ": expected finite numbers (m)");
}

// Column-major 4x4 matrices, as OpenGL takes them.
using Mat4 = std::array<double, 16>;

Mat4 multiply(const Mat4& a, const Mat4& b) {
    Mat4 c{};
    for (int col = 0; col < 4; ++col)
        for (int row = 0; row < 4; ++row) {
            double s = 0;
            for (int k = 0; k < 4; ++k) s += a[k * 4 + row] * b[col * 4 + k];
            c[col * 4 + row] = s;
        }
    return c;
}

Vec4 apply(const Mat4& m, const Vec3& p) {
    Vec4 r;
    for (int row = 0; row < 4; ++row)
        r[row] = m[row] * p[0] + m[4 + row] * p[1] + m[8 + row] * p[2] + m[12 + row];
    return r;
}

// World-to-eye transform of a camera at position looking at lookAt (OpenGL: eye looks down -z).
Mat4 calcViewMatrix(const Camera& c) {
    const Vec3 f = (c.lookAt - c.position).normalize();
    const Vec3 s = SimTK::cross(f, c.up).normalize();
    const Vec3 u = SimTK::cross(s, f);
    Mat4 m{};
    for (int i = 0; i < 3; ++i) {
        m[i * 4 + 0] = s[i];
        m[i * 4 + 1] = u[i];
        m[i * 4 + 2] = -f[i];
    }
    m[12] = -SimTK::dot(s, c.position);
    m[13] = -SimTK::dot(u, c.position);
    m[14] = SimTK::dot(f, c.position);
    m[15] = 1;
    return m;
}

// Same matrices as glFrustum / glOrtho.
Mat4 calcProjectionMatrix(const Camera& c, double aspect) {
    const double n = c.nearClip, f = c.farClip;
    Mat4 m{};
    if (c.orthographic) {
        const double hh = 0.5 * c.orthoHeight, hw = hh * aspect;
        m[0] = 1 / hw;
        m[5] = 1 / hh;
        m[10] = -2 / (f - n);
        m[14] = -(f + n) / (f - n);
        m[15] = 1;
    } else {
        const double hh = n * std::tan(0.5 * c.verticalFov), hw = hh * aspect;
        m[0] = n / hw;
        m[5] = n / hh;
        m[10] = -(f + n) / (f - n);
        m[11] = -1;
        m[14] = -2 * f * n / (f - n);
    }
    return m;
}

// Placement X_GD followed by a per-axis scale, as a column-major matrix.
Mat4 calcModelMatrix(const Transform& X, const Vec3& scale) {
    Mat4 m{};
    const SimTK::Mat33 R = X.R().asMat33();
    for (int col = 0; col < 3; ++col)
        for (int row = 0; row < 3; ++row) m[col * 4 + row] = R(row, col) * scale[col];
    for (int row = 0; row < 3; ++row) m[12 + row] = X.p()[row];
    m[15] = 1;
    return m;
}

// One thing to draw, already placed in Ground.
struct Primitive {
    const TriMesh* mesh = nullptr;            // solids: a cached unit mesh ...
    std::shared_ptr<const TriMesh> ownMesh;   // ... or a per-frame mesh (torus, polygonal mesh)
    Mat4 model{};                             // solids: unit mesh -> Ground
    std::vector<float> lines;                 // lines: xyz pairs in Ground
    Vec4 color;                               // RGBA in [0, 1]
    int representation = SimTK::DecorativeGeometry::DrawSurface;
    double lineThickness = 1;                 // output pixels
    Vec3 anchor_G;                            // point used to sort translucent primitives
};

}  // namespace

void RenderSettings::validate() const {
    checkEvenSize("width", width);
    checkEvenSize("height", height);
    checkField("supersample", supersample, Bound::closed(1, kMaxSupersample));
    checkField("max_tile_side", maxTileSide, Bound::closed(64, kMaxBufferSide, "px"));
    if (width * supersample > kMaxBufferSide || height * supersample > kMaxBufferSide)
        throw FieldError("supersample", "= " + std::to_string(supersample) +
                                            ": expected width*supersample and height*supersample <= " +
                                            std::to_string(kMaxBufferSide) + " px (frame is " +
                                            std::to_string(width) + "x" + std::to_string(height) + ")");
    checkUnitColor("background", background);
    checkField("default_line_thickness", defaultLineThickness,
               {0, kMaxLineThickness, true, false, "px"});
    checkField("ambient", ambient, Bound::closed(0, 1));
    checkField("diffuse", diffuse, Bound::closed(0, 1));

    checkFiniteVec("camera.position", camera.position);
    checkFiniteVec("camera.look_at", camera.lookAt);
    checkFiniteVec("camera.up", camera.up);
    const Vec3 view = camera.lookAt - camera.position;
    if (!(view.norm() > 1e-9))
        throw FieldError("camera.look_at", "= " + formatVec(camera.lookAt) +
                                               ": expected a point different from camera.position");
    const double upNorm = camera.up.norm();
    if (!(upNorm > 1e-9) || SimTK::cross(view / view.norm(), camera.up / upNorm).norm() < 1e-6)
        throw FieldError("camera.up", "= " + formatVec(camera.up) +
                                          ": expected a nonzero direction not parallel to look_at - position");
    // Lower bounds: a view of under 1 cm (or 0.01 rad) shows a speck of the arm, if any of it.
    if (camera.orthographic)
        checkField("camera.ortho_height", camera.orthoHeight, Bound{0.01, 1e3, false, false, "m"});
    else
        checkField("camera.vertical_fov", camera.verticalFov, Bound{0.01, kPi, false, true, "rad"});
    checkField("camera.near_clip", camera.nearClip, Bound::positive("m"));
    checkField("camera.far_clip", camera.farClip, {camera.nearClip, 1e300, true, false, "m, beyond near_clip"});
    // The point looked at lies inside the clip range, or the frame is empty (a position in mm, say).
    const double distance = view.norm();
    if (!(distance > camera.nearClip && distance < camera.farClip))
        throw FieldError("camera.position", "= " + formatVec(camera.position) + ": " + formatNumber(distance, 4) +
                                                " m from look_at, outside the clip range (" + formatNumber(camera.nearClip) +
                                                ", " + formatNumber(camera.farClip) + ") m: expected the point looked at "
                                                "between near_clip and far_clip (positions in m)");
}

RenderSettings readRenderSettings(const ParamNode& node) {
    RenderSettings s;
    auto readVec3 = [](const ParamNode& n, const std::string& key, const Vec3& def, const Bound& bound) {
        if (!n.has(key)) return def;
        const std::vector<double> v = n.getNumbers(key, bound);
        if (v.size() != 3)
            throw InputError(n.where(key) + ": field " + describeField(n.path(key)) + " has " + std::to_string(v.size()) +
                             " numbers: expected 3");
        return Vec3(v[0], v[1], v[2]);
    };
    s.width = node.getInt("width", kMinSize, kMaxSize, s.width);
    s.height = node.getInt("height", kMinSize, kMaxSize, s.height);
    s.supersample = node.getInt("supersample", 1, kMaxSupersample, s.supersample);
    s.background = readVec3(node, "background", s.background, Bound::closed(0, 1));
    s.defaultLineThickness = node.getNumber("default_line_thickness",
                                            {0, kMaxLineThickness, true, false, "px"}, s.defaultLineThickness);
    s.ambient = node.getNumber("ambient", Bound::closed(0, 1), s.ambient);
    s.diffuse = node.getNumber("diffuse", Bound::closed(0, 1), s.diffuse);
    if (node.has("camera")) {
        const ParamNode c = node.child("camera");
        s.camera.position = readVec3(c, "position", s.camera.position, Bound::any("m"));
        s.camera.lookAt = readVec3(c, "look_at", s.camera.lookAt, Bound::any("m"));
        s.camera.up = readVec3(c, "up", s.camera.up, Bound::any());
        s.camera.orthographic = c.getBool("orthographic", s.camera.orthographic);
        s.camera.verticalFov = c.getNumber("vertical_fov", Bound{0.01, kPi, false, true, "rad"}, s.camera.verticalFov);
        s.camera.orthoHeight = c.getNumber("ortho_height", Bound{0.01, 1e3, false, false, "m"}, s.camera.orthoHeight);
        s.camera.nearClip = c.getNumber("near_clip", Bound::positive("m"), s.camera.nearClip);
        s.camera.farClip = c.getNumber("far_clip", Bound::positive("m"), s.camera.farClip);
        // A key the chosen projection would ignore is refused, as options that would be ignored are.
        const char* unused = s.camera.orthographic ? "vertical_fov" : "ortho_height";
        if (c.has(unused))
            throw InputError(c.where(unused) + ": field " + describeField(c.path(unused)) + " is ignored by " +
                             (s.camera.orthographic ? "an orthographic camera (orthographic: true sets the view by "
                                                      "ortho_height)"
                                                    : "a perspective camera (it applies with orthographic: true)"));
        c.finish();
    }
    node.finish();
    node.rethrowWithLocation([&] { s.validate(); });
    return s;
}

SimTK::Vec2 projectToPixel(const Camera& camera, int width, int height, const Vec3& p_G) {
    const Mat4 pv = multiply(calcProjectionMatrix(camera, double(width) / height), calcViewMatrix(camera));
    const Vec4 clip = apply(pv, p_G);
    if (!(clip[3] > 0)) return SimTK::Vec2(std::numeric_limits<double>::quiet_NaN());
    const double x = clip[0] / clip[3], y = clip[1] / clip[3];
    return {0.5 * (x + 1) * width, 0.5 * (1 - y) * height};
}

// --------------------------------------------------------------------------------------------------
// Turning DecorativeGeometry into primitives.

namespace {

enum class UnitShape { Sphere, Cylinder, Cone, Brick, Disk };

class MeshCache {
public:
    const TriMesh* get(UnitShape shape, int level) {
        auto key = std::make_pair(int(shape), shape == UnitShape::Brick ? 0 : level);
        auto it = meshes_.find(key);
        if (it != meshes_.end()) return &it->second;
        TriMesh m;
        switch (shape) {
        case UnitShape::Sphere: m = render_detail::makeSphere(level); break;
        case UnitShape::Cylinder: m = render_detail::makeCylinder(level); break;
        case UnitShape::Cone: m = render_detail::makeCone(level); break;
        case UnitShape::Brick: m = render_detail::makeBrick(); break;
        case UnitShape::Disk: m = render_detail::makeDisk(level); break;
        }
        return &meshes_.emplace(key, std::move(m)).first->second;
    }

private:
    std::map<std::pair<int, int>, TriMesh> meshes_;
};

// Visits DecorativeGeometry (Decorations composites are expanded by Simbody) and records primitives
// placed in Ground: X_GD = X_GB(state) * X_BD, as Simbody's own visualizer does.
class GeometryCollector : public SimTK::DecorativeGeometryImplementation {
public:
    GeometryCollector(const SimTK::SimbodyMatterSubsystem* matter, const SimTK::State* state,
                      MeshCache& cache, double defaultLineThickness, std::vector<Primitive>& out)
        : matter_(matter), state_(state), cache_(cache), defaultLineThickness_(defaultLineThickness),
          out_(out) {}

    void implementPointGeometry(const SimTK::DecorativePoint& g) override {
        const Transform X = calcX_GD(g);
        const Vec3 s = calcScale(g), p = X * g.getPoint();
        Primitive prim = makeLines(g, kDefaultPointColor);
        for (int axis = 0; axis < 3; ++axis) {
            const Vec3 d = kPointArmLength * s[axis] * Vec3(X.R().col(axis));
            appendLine(prim, p - d, p + d);
        }
        prim.anchor_G = p;
        push(std::move(prim));
    }
    void implementLineGeometry(const SimTK::DecorativeLine& g) override {
        const Transform X = calcX_GD(g);
        Primitive prim = makeLines(g, kDefaultColor);
        appendLine(prim, X * g.getPoint1(), X * g.getPoint2());
        prim.anchor_G = X * (0.5 * (g.getPoint1() + g.getPoint2()));
        push(std::move(prim));
    }
    void implementBrickGeometry(const SimTK::DecorativeBrick& g) override {
        pushSolid(g, cache_.get(UnitShape::Brick, 0), calcX_GD(g),
                  calcScale(g).elementwiseMultiply(g.getHalfLengths()));
    }
    void implementCylinderGeometry(const SimTK::DecorativeCylinder& g) override {
        const Vec3 s = calcScale(g);
        pushSolid(g, cache_.get(UnitShape::Cylinder, level(g)), calcX_GD(g),
                  Vec3(s[0] * g.getRadius(), s[1] * g.getHalfHeight(), s[2] * g.getRadius()));
    }
    void implementCircleGeometry(const SimTK::DecorativeCircle& g) override {
        const Vec3 s = calcScale(g);
        pushSolid(g, cache_.get(UnitShape::Disk, level(g)), calcX_GD(g),
                  Vec3(s[0] * g.getRadius(), s[1] * g.getRadius(), 1));
    }
    void implementSphereGeometry(const SimTK::DecorativeSphere& g) override {
        pushSolid(g, cache_.get(UnitShape::Sphere, level(g)), calcX_GD(g), g.getRadius() * calcScale(g));
    }
    void implementEllipsoidGeometry(const SimTK::DecorativeEllipsoid& g) override {
        pushSolid(g, cache_.get(UnitShape::Sphere, level(g)), calcX_GD(g),
                  calcScale(g).elementwiseMultiply(g.getRadii()));
    }
    void implementFrameGeometry(const SimTK::DecorativeFrame& g) override {
        // Three axes from the origin; x, y, z in red, green, blue unless a colour is given.
        const Transform X = calcX_GD(g);
        const Vec3 s = calcScale(g);
        static const Vec3 axisColors[3] = {Vec3(1, 0, 0), Vec3(0, 0.7, 0), Vec3(0, 0, 1)};
        for (int axis = 0; axis < 3; ++axis) {
            Primitive prim = makeLines(g, axisColors[axis]);
            appendLine(prim, X.p(), X.p() + g.getAxisLength() * s[axis] * Vec3(X.R().col(axis)));
            prim.anchor_G = X.p();
            push(std::move(prim));
        }
    }
    void implementTextGeometry(const SimTK::DecorativeText&) override {}
    void implementMeshGeometry(const SimTK::DecorativeMesh& g) override {
        pushMesh(g, g.getMesh());
    }
    void implementMeshFileGeometry(const SimTK::DecorativeMeshFile& g) override {
        const SimTK::PolygonalMesh* mesh = nullptr;
        try {
            mesh = &g.getMesh();
        } catch (const std::exception& e) {
            throw InputError("mesh file '" + g.getMeshFile() + "': cannot be loaded: " + e.what());
        }
        pushMesh(g, *mesh);
    }
    void implementTorusGeometry(const SimTK::DecorativeTorus& g) override {
        Primitive prim = makeSolid(g);
        prim.ownMesh = std::make_shared<TriMesh>(
            render_detail::makeTorus(g.getTorusRadius(), g.getTubeRadius(), level(g)));
        const Transform X = calcX_GD(g);
        prim.model = calcModelMatrix(X, calcScale(g));
        prim.anchor_G = X.p();
        push(std::move(prim));
    }
    void implementArrowGeometry(const SimTK::DecorativeArrow& g) override {
        // Shaft: a line of the arrow's thickness; head: a solid cone of height tipLength.
        const Transform X = calcX_GD(g);
        const Vec3 start = X * g.getStartPoint(), end = X * g.getEndPoint();
        const double length = (end - start).norm();
        if (!(length > 0)) return;
        const Vec3 dir = (end - start) / length;
        const double tip = std::min(g.getTipLength(), length);
        const Vec3 headBase = end - tip * dir;
        if (tip < length) {
            Primitive shaft = makeLines(g, kDefaultColor);
            appendLine(shaft, start, headBase);
            shaft.anchor_G = 0.5 * (start + headBase);
            push(std::move(shaft));
        }
        if (tip > 0) {
            const Transform X_cone(SimTK::Rotation(SimTK::UnitVec3(dir), SimTK::YAxis), headBase);
            const double r = kArrowHeadRadiusRatio * tip;
            pushSolid(g, cache_.get(UnitShape::Cone, level(g)), X_cone, Vec3(r, tip, r));
        }
    }
    void implementConeGeometry(const SimTK::DecorativeCone& g) override {
        const Transform X = calcX_GD(g);
        const Transform X_DC(SimTK::Rotation(g.getDirection(), SimTK::YAxis), g.getOrigin());
        const Vec3 s = calcScale(g);
        pushSolid(g, cache_.get(UnitShape::Cone, level(g)), X * X_DC,
                  Vec3(s[0] * g.getBaseRadius(), s[1] * g.getHeight(), s[2] * g.getBaseRadius()));
    }

private:
    Transform calcX_GD(const SimTK::DecorativeGeometry& g) const {
        const int id = g.getBodyId();
        if (id == 0) return g.getTransform();
        const int numBodies = matter_ ? matter_->getNumBodies() : 1;
        if (id < 0 || id >= numBodies)
            throw InputError("decoration body id " + std::to_string(id) +
                             ": expected a MobilizedBodyIndex in [0, " + std::to_string(numBodies - 1) +
                             "] of the rendered system");
        return matter_->getMobilizedBody(SimTK::MobilizedBodyIndex(id)).getBodyTransform(*state_) *
               g.getTransform();
    }
    static Vec3 calcScale(const SimTK::DecorativeGeometry& g) {
        Vec3 s = g.getScaleFactors();
        for (int i = 0; i < 3; ++i)
            if (!(s[i] > 0)) s[i] = 1;
        return s;
    }
    static int level(const SimTK::DecorativeGeometry& g) {
        return render_detail::calcTessellationLevel(g.getResolution());
    }
    static Vec4 calcColor(const SimTK::DecorativeGeometry& g, const Vec3& defaultColor) {
        const Vec3 c = g.getColor()[0] >= 0 ? g.getColor() : defaultColor;
        const double a = g.getOpacity() < 0 ? 1 : std::min(1.0, g.getOpacity());
        return {c[0], c[1], c[2], a};
    }
    Primitive makeSolid(const SimTK::DecorativeGeometry& g) const {
        Primitive p;
        p.color = calcColor(g, kDefaultColor);
        p.representation = g.getRepresentation() == SimTK::DecorativeGeometry::DrawDefault
                               ? int(SimTK::DecorativeGeometry::DrawSurface)
                               : int(g.getRepresentation());
        p.lineThickness = g.getLineThickness() > 0 ? g.getLineThickness() : 1.0;
        return p;
    }
    Primitive makeLines(const SimTK::DecorativeGeometry& g, const Vec3& defaultColor) const {
        Primitive p;
        p.color = calcColor(g, defaultColor);
        p.representation = g.getRepresentation() == SimTK::DecorativeGeometry::Hide
                               ? int(SimTK::DecorativeGeometry::Hide)
                               : int(SimTK::DecorativeGeometry::DrawWireframe);
        p.lineThickness = g.getLineThickness() > 0 ? g.getLineThickness() : defaultLineThickness_;
        return p;
    }
    static void appendLine(Primitive& p, const Vec3& a, const Vec3& b) {
        for (int i = 0; i < 3; ++i) p.lines.push_back(float(a[i]));
        for (int i = 0; i < 3; ++i) p.lines.push_back(float(b[i]));
    }
    void pushSolid(const SimTK::DecorativeGeometry& g, const TriMesh* mesh, const Transform& X_GD,
                   const Vec3& scale) {
        Primitive p = makeSolid(g);
        p.mesh = mesh;
        p.model = calcModelMatrix(X_GD, scale);
        p.anchor_G = X_GD.p();
        push(std::move(p));
    }
    void pushMesh(const SimTK::DecorativeGeometry& g, const SimTK::PolygonalMesh& mesh) {
        Primitive p = makeSolid(g);
        p.ownMesh = std::make_shared<TriMesh>(render_detail::makeFromPolygonalMesh(mesh));
        const Transform X = calcX_GD(g);
        p.model = calcModelMatrix(X, calcScale(g));
        p.anchor_G = X.p();
        push(std::move(p));
    }
    void push(Primitive&& p) {
        if (p.representation == SimTK::DecorativeGeometry::Hide || p.color[3] <= 0) return;
        out_.push_back(std::move(p));
    }

    const SimTK::SimbodyMatterSubsystem* matter_;
    const SimTK::State* state_;
    MeshCache& cache_;
    double defaultLineThickness_;
    std::vector<Primitive>& out_;
};

}  // namespace

// --------------------------------------------------------------------------------------------------
// OSMesa drawing.

// A frame is drawn in tiles of at most maxTileSide supersampled pixels a side, so OSMesa's buffers
// (ours, its colour copy and depth) stay small: 5 MB at 1280 x 720 supersampled twice (12 tiles),
// instead of 44 MB for one 2560 x 1440 buffer (docs/benchmarks.md, issue 30). Each tile's
// projection maps its part of the picture, with a margin as wide as half the widest line, onto the
// whole buffer, and the margin is dropped: tile edges fall on pixel edges of the supersampled grid and
// lines (clipped by their centre) are whole, so tiles join without seams.
struct OffscreenRenderer::Impl {
    RenderSettings settings;
    int tilesX = 1, tilesY = 1;
    int tileWidth = 0, tileHeight = 0;      // output pixels per tile (the last tile may use fewer)
    int margin = 0;                         // output pixels drawn around a tile and dropped (wide lines
                                            // are clipped by their centre: without it they lose their
                                            // half beyond a tile's edge)
    int bufferWidth = 0, bufferHeight = 0;  // (tile + 2 margin) * supersample
    OSMesaContext context = nullptr;
    std::vector<unsigned char> buffer;  // RGBA, top row first
    MeshCache meshes;
    std::vector<Primitive> primitives, topPrimitives;
    cv::Mat downsampled;                // RGBA at tile size, reused
    cv::Mat frame;                      // BGR at output size, reused when the caller let go of it
    float maxLineWidth = 1;

    explicit Impl(const RenderSettings& s) : settings(s) {
        settings.validate();
        const int ss = settings.supersample;
        const int side = settings.maxTileSide;
        tilesX = std::max(1, (settings.width * ss + side - 1) / side);
        tilesY = std::max(1, (settings.height * ss + side - 1) / side);
        tileWidth = (settings.width + tilesX - 1) / tilesX;
        tileHeight = (settings.height + tilesY - 1) / tilesY;
        context = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr);
        if (!context) throw std::runtime_error("OSMesa: could not create an RGBA context with a depth buffer");
        setMargin(0);
        makeCurrent();
        GLint maxWidth = 0, maxHeight = 0;
        OSMesaGetIntegerv(OSMESA_MAX_WIDTH, &maxWidth);
        OSMesaGetIntegerv(OSMESA_MAX_HEIGHT, &maxHeight);
        if (bufferWidth > maxWidth || bufferHeight > maxHeight) {
            OSMesaDestroyContext(context);
            throw std::runtime_error("OSMesa: render buffer " + std::to_string(bufferWidth) + "x" +
                                     std::to_string(bufferHeight) + " exceeds the maximum " +
                                     std::to_string(maxWidth) + "x" + std::to_string(maxHeight));
        }
        GLfloat range[2] = {1, 1};
        glGetFloatv(GL_ALIASED_LINE_WIDTH_RANGE, range);
        maxLineWidth = range[1];
        if (tilesX * tilesY > 1) setMargin(calcMargin(settings.defaultLineThickness));   // made current per frame
    }
    ~Impl() {
        if (!context) return;
        if (OSMesaGetCurrentContext() == context) OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0);
        OSMesaDestroyContext(context);
    }

    // Output pixels a line of this thickness (and a point) reaches beyond its centre, plus one.
    int calcMargin(double lineThickness) const {
        const int ss = settings.supersample;
        const double widest = std::max<double>({std::clamp(float(lineThickness) * ss, 1.0f, maxLineWidth), 2.0 * ss});
        return int(std::ceil(0.5 * widest / ss)) + 1;
    }
    void setMargin(int m) {
        margin = m;
        bufferWidth = (tileWidth + 2 * m) * settings.supersample;
        bufferHeight = (tileHeight + 2 * m) * settings.supersample;
        buffer.assign(size_t(bufferWidth) * bufferHeight * 4, 0);
    }

    void makeCurrent() {
        if (!OSMesaMakeCurrent(context, buffer.data(), GL_UNSIGNED_BYTE, bufferWidth, bufferHeight))
            throw std::runtime_error("OSMesa: could not make the context current");
        OSMesaPixelStore(OSMESA_Y_UP, 0);
    }

    void setupScene(const Mat4& projection, const Mat4& view) {
        const RenderSettings& s = settings;
        glViewport(0, 0, bufferWidth, bufferHeight);
        glClearColor(GLfloat(s.background[0]), GLfloat(s.background[1]), GLfloat(s.background[2]), 1);
        glClearDepth(1);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LEQUAL);
        glDisable(GL_CULL_FACE);
        glDisable(GL_DITHER);
        glShadeModel(GL_SMOOTH);
        glEnable(GL_NORMALIZE);

        glMatrixMode(GL_PROJECTION);
        glLoadMatrixd(projection.data());
        glMatrixMode(GL_MODELVIEW);
        glLoadIdentity();
        // A key light fixed to the camera, from above-left-front, and ambient fill.
        const GLfloat lightDir[4] = {-0.35f, 0.55f, 1.0f, 0.0f};
        const GLfloat d = GLfloat(s.diffuse), a = GLfloat(s.ambient);
        const GLfloat diffuse[4] = {d, d, d, 1}, ambient[4] = {a, a, a, 1}, black[4] = {0, 0, 0, 1};
        const GLfloat specular[4] = {0.25f, 0.25f, 0.25f, 1};
        glLightfv(GL_LIGHT0, GL_POSITION, lightDir);
        glLightfv(GL_LIGHT0, GL_DIFFUSE, diffuse);
        glLightfv(GL_LIGHT0, GL_SPECULAR, specular);
        glLightfv(GL_LIGHT0, GL_AMBIENT, black);
        glLightModelfv(GL_LIGHT_MODEL_AMBIENT, ambient);
        glLightModeli(GL_LIGHT_MODEL_TWO_SIDE, GL_FALSE);
        glEnable(GL_LIGHT0);
        glEnable(GL_COLOR_MATERIAL);
        glColorMaterial(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE);
        glMaterialfv(GL_FRONT_AND_BACK, GL_SPECULAR, specular);
        glMaterialf(GL_FRONT_AND_BACK, GL_SHININESS, 40);
        glLoadMatrixd(view.data());
    }

    void draw(const Primitive& p) {
        const float ss = float(settings.supersample);
        glColor4d(p.color[0], p.color[1], p.color[2], p.color[3]);
        const float lineWidth = std::clamp(float(p.lineThickness) * ss, 1.0f, maxLineWidth);
        if (!p.lines.empty()) {
            glDisable(GL_LIGHTING);
            glLineWidth(lineWidth);
            glEnableClientState(GL_VERTEX_ARRAY);
            glVertexPointer(3, GL_FLOAT, 0, p.lines.data());
            glDrawArrays(GL_LINES, 0, GLsizei(p.lines.size() / 3));
            glDisableClientState(GL_VERTEX_ARRAY);
            return;
        }
        const TriMesh* mesh = p.ownMesh ? p.ownMesh.get() : p.mesh;
        if (!mesh || mesh->getNumVertices() == 0) return;
        glEnable(GL_LIGHTING);
        switch (p.representation) {
        case SimTK::DecorativeGeometry::DrawPoints:
            glPointSize(std::max(1.0f, 2 * ss));
            glPolygonMode(GL_FRONT_AND_BACK, GL_POINT);
            break;
        case SimTK::DecorativeGeometry::DrawWireframe:
            glLineWidth(lineWidth);
            glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
            break;
        default:
            glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
        }
        glPushMatrix();
        glMultMatrixd(p.model.data());
        glInterleavedArrays(GL_N3F_V3F, 0, mesh->data.data());
        glDrawArrays(mesh->mode == TriMesh::Quads ? GL_QUADS : GL_TRIANGLES, 0, mesh->getNumVertices());
        glDisableClientState(GL_NORMAL_ARRAY);
        glDisableClientState(GL_VERTEX_ARRAY);
        glPopMatrix();
        glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    }

    // Opaque first, then translucent back to front without depth writes.
    void drawLayer(const std::vector<Primitive>& layer, const Mat4& view) {
        std::vector<std::pair<double, const Primitive*>> translucent;
        for (const Primitive& p : layer) {
            if (p.color[3] < 1)
                translucent.emplace_back(apply(view, p.anchor_G)[2], &p);
            else
                draw(p);
        }
        if (translucent.empty()) return;
        std::stable_sort(translucent.begin(), translucent.end(),
                         [](const auto& a, const auto& b) { return a.first < b.first; });
        glEnable(GL_BLEND);
        glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
        glDepthMask(GL_FALSE);
        for (const auto& t : translucent) draw(*t.second);
        glDepthMask(GL_TRUE);
        glDisable(GL_BLEND);
    }

    // Draws geometry and extra, then (after clearing depth) onTop.
    cv::Mat render(const SimTK::SimbodyMatterSubsystem* matter, const SimTK::State* state,
                   const SimTK::Array_<SimTK::DecorativeGeometry>& geometry,
                   const std::vector<SimTK::DecorativeGeometry>& extra,
                   const SimTK::Array_<SimTK::DecorativeGeometry>& onTop = {}) {
        primitives.clear();
        topPrimitives.clear();
        GeometryCollector collector(matter, state, meshes, settings.defaultLineThickness, primitives);
        for (const auto& g : geometry) g.implementGeometry(collector);
        for (const auto& g : extra) g.implementGeometry(collector);
        GeometryCollector topCollector(matter, state, meshes, settings.defaultLineThickness, topPrimitives);
        for (const auto& g : onTop) g.implementGeometry(topCollector);

        if (tilesX * tilesY > 1) {   // a frame with wider lines than any before: a wider margin
            double thickest = settings.defaultLineThickness;
            for (const auto* layer : {&primitives, &topPrimitives})
                for (const Primitive& p : *layer) thickest = std::max(thickest, p.lineThickness);
            if (calcMargin(thickest) > margin) setMargin(calcMargin(thickest));
        }
        makeCurrent();
        const Camera& cam = settings.camera;
        const Mat4 view = calcViewMatrix(cam);
        const Mat4 projection = calcProjectionMatrix(cam, double(settings.width) / settings.height);
        const int ss = settings.supersample, width = settings.width, height = settings.height;
        // The frame buffer is reused while no caller holds the previous frame (no 2.7 MB allocation
        // and page faults per frame at 1280 x 720).
        if (frame.empty() || frame.u->refcount > 1) frame = cv::Mat(height, width, CV_8UC3);
        cv::Mat& out = frame;
        for (int row = 0; row < tilesY; ++row) {
            for (int col = 0; col < tilesX; ++col) {
                checkInterruption();   // a large frame takes seconds: a stop waits one tile at most
                const int x = col * tileWidth, y = row * tileHeight;
                if (x >= width || y >= height) continue;
                // The tile and its margin in normalized device coordinates (y up), stretched onto [-1, 1].
                const double x0 = -1 + 2.0 * (x - margin) / width, x1 = -1 + 2.0 * (x + tileWidth + margin) / width;
                const double y1 = 1 - 2.0 * (y - margin) / height, y0 = 1 - 2.0 * (y + tileHeight + margin) / height;
                Mat4 tile{};
                tile[0] = 2 / (x1 - x0);
                tile[5] = 2 / (y1 - y0);
                tile[10] = 1;
                tile[12] = -(x0 + x1) / (x1 - x0);
                tile[13] = -(y0 + y1) / (y1 - y0);
                tile[15] = 1;
                setupScene(multiply(tile, projection), view);
                drawLayer(primitives, view);
                if (!topPrimitives.empty()) {
                    glClear(GL_DEPTH_BUFFER_BIT);
                    drawLayer(topPrimitives, view);
                }
                glFinish();
                // Downsample first (channels are independent), then drop alpha and swap to BGR.
                const cv::Mat rgba(bufferHeight, bufferWidth, CV_8UC4, buffer.data());
                const cv::Rect part(margin, margin, std::min(tileWidth, width - x), std::min(tileHeight, height - y));
                cv::Mat target = out(cv::Rect(x, y, part.width, part.height));
                if (ss == 1) {
                    cv::cvtColor(rgba(part), target, cv::COLOR_RGBA2BGR);
                } else {
                    cv::resize(rgba, downsampled, cv::Size(tileWidth + 2 * margin, tileHeight + 2 * margin), 0, 0,
                               cv::INTER_AREA);
                    cv::cvtColor(downsampled(part), target, cv::COLOR_RGBA2BGR);
                }
            }
        }
        return out;
    }
};

OffscreenRenderer::OffscreenRenderer(const RenderSettings& settings)
    : impl_(std::make_unique<Impl>(settings)) {}
OffscreenRenderer::~OffscreenRenderer() = default;
OffscreenRenderer::OffscreenRenderer(OffscreenRenderer&&) noexcept = default;
OffscreenRenderer& OffscreenRenderer::operator=(OffscreenRenderer&&) noexcept = default;

const RenderSettings& OffscreenRenderer::getSettings() const { return impl_->settings; }

cv::Mat OffscreenRenderer::renderFrame(const SimTK::MultibodySystem& system, const SimTK::State& state,
                                       const std::vector<SimTK::DecorativeGeometry>& extra) {
    if (state.getSystemStage() < SimTK::Stage::Position) system.realize(state, SimTK::Stage::Position);
    SimTK::Array_<SimTK::DecorativeGeometry> geometry;
    for (SimTK::Stage stage = SimTK::Stage::Topology; stage <= state.getSystemStage(); ++stage)
        system.calcDecorativeGeometryAndAppend(state, stage, geometry);
    return impl_->render(&system.getMatterSubsystem(), &state, geometry, extra);
}

cv::Mat OffscreenRenderer::renderLayers(const SimTK::MultibodySystem& system, const SimTK::State& state,
                                        const SimTK::Array_<SimTK::DecorativeGeometry>& geometry,
                                        const SimTK::Array_<SimTK::DecorativeGeometry>& onTop) {
    if (state.getSystemStage() < SimTK::Stage::Position)
        throw std::logic_error("OffscreenRenderer::renderLayers: realize the state to Stage::Position first");
    return impl_->render(&system.getMatterSubsystem(), &state, geometry, {}, onTop);
}

cv::Mat OffscreenRenderer::renderGeometry(const std::vector<SimTK::DecorativeGeometry>& geometry) {
    return impl_->render(nullptr, nullptr, {}, geometry);
}

}  // namespace armsim
