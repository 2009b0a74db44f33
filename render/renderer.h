// Offscreen rendering of any Simbody MultibodySystem through OSMesa (no X display, no libGL).
//
// The renderer draws what the system says about itself: every subsystem's
// calcDecorativeGeometryAndAppend() output (body decorations added with addBodyDecoration, a
// DecorationSubsystem's geometry, and whatever force elements such as a muscle path emit), placed by
// the body poses in the State, plus optional extra geometry from the caller (a bench or floor for
// scale). Supported: DecorativeLine (thickness), Sphere, Ellipsoid, Brick, Cylinder, Cone, Circle,
// Torus, Mesh, MeshFile, Frame, Arrow, Point, and Decorations composites; DecorativeText is skipped.
// Colour, opacity (translucent geometry is blended after the opaque pass), scale factors (solids,
// frames, points; lines and arrows are placed by their end points), resolution (tessellation) and
// representation (points / wireframe / surface / hide) are applied. Solids are lit by a
// camera-fixed key light plus ambient (fixed-function GL 1.x); lines are unlit, thickness in pixels.
//
// Anti-aliasing is by supersampling: the scene is rendered at `supersample` times the frame size and
// reduced with cv::resize(INTER_AREA), i.e. each output pixel is the mean of a supersample^2 block.
// Rendering is deterministic: the same state and settings give identical pixels.
#pragma once

#include "muscles/simbody.h"

#include <opencv2/core.hpp>

#include <memory>
#include <vector>

namespace armsim {

class ParamNode;

/// A camera fixed in Ground. The defaults look at the Ground x-y plane (the arm's sagittal plane)
/// from +z with y up.
struct Camera {
    SimTK::Vec3 position{0, 0, 2};   ///< eye point in Ground (m)
    SimTK::Vec3 lookAt{0, 0, 0};     ///< point that appears at the frame centre (m)
    SimTK::Vec3 up{0, 1, 0};         ///< direction that appears upward; not parallel to the view (-)
    bool orthographic = false;       ///< false: perspective (verticalFov); true: parallel (orthoHeight)
    double verticalFov = 0.7;        ///< full vertical field of view, perspective only (rad), in (0, pi)
    double orthoHeight = 1.0;        ///< height of the visible region, orthographic only (m), > 0
    double nearClip = 0.01;          ///< distance of the near clipping plane (m), > 0
    double farClip = 100.0;          ///< distance of the far clipping plane (m), > nearClip
};

/// Everything that determines a rendered frame besides the system and state.
struct RenderSettings {
    int width = 1280;                       ///< frame width (px), even, in [16, 4096]
    int height = 720;                       ///< frame height (px), even, in [16, 4096]
    Camera camera;                          ///< fixed viewpoint
    SimTK::Vec3 background{0.96, 0.96, 0.96};  ///< background colour, RGB each in [0, 1]
    int supersample = 2;                    ///< anti-aliasing factor, in [1, 4] (1 = off); the
                                            ///< render buffer (size x factor) is at most 8192 px a side
    double defaultLineThickness = 2.0;      ///< thickness of lines that do not set one (px), in (0, 64]
    double ambient = 0.35;                  ///< ambient light intensity (-), in [0, 1]
    double diffuse = 0.75;                  ///< intensity of the camera-fixed key light (-), in [0, 1]
    int maxTileSide = 640;                  ///< the frame is drawn in tiles of at most this many
                                            ///< supersampled px a side (bounds OSMesa's buffers to
                                            ///< ~5 MB; 44 MB whole at 1280 x 720 x 2), in [64, 8192];
                                            ///< C++ only (not a YAML key)

    /// Throws FieldError naming the field (YAML key, e.g. "camera.vertical_fov"), its value and the
    /// violated bound.
    void validate() const;
};

/// Reads RenderSettings from a YAML mapping. Every key is optional (defaults above); unknown keys
/// are errors. Keys: width, height, supersample, background [r, g, b], default_line_thickness,
/// ambient, diffuse, camera {position [x, y, z], look_at, up, orthographic, vertical_fov (rad),
/// ortho_height (m), near_clip, far_clip}. Errors name the file, line, field and value.
RenderSettings readRenderSettings(const ParamNode& node);

/// Where a Ground point p_G appears in a frame rendered with camera at width x height: x to the
/// right and y downward from the frame's top-left corner in pixels (pixel (i, j) covers
/// [i, i+1) x [j, j+1)). Returns NaN coordinates for a point behind a perspective camera.
/// Uses the same matrices as the renderer.
SimTK::Vec2 projectToPixel(const Camera& camera, int width, int height, const SimTK::Vec3& p_G);

/// Renders frames of Simbody systems into OpenCV images with an OSMesa context it owns.
/// Use one renderer per thread (OSMesa contexts are bound per thread); each call binds it again, so
/// several renderers may take turns on one thread. Move-only.
class OffscreenRenderer {
public:
    /// Validates settings (throws FieldError) and creates the OSMesa context and buffer; throws
    /// std::runtime_error if OSMesa cannot create a context of that size.
    explicit OffscreenRenderer(const RenderSettings& settings);
    ~OffscreenRenderer();
    OffscreenRenderer(OffscreenRenderer&&) noexcept;
    OffscreenRenderer& operator=(OffscreenRenderer&&) noexcept;
    OffscreenRenderer(const OffscreenRenderer&) = delete;
    OffscreenRenderer& operator=(const OffscreenRenderer&) = delete;

    /// Draws system's decorations in state, followed by extra (placed like system geometry: in the
    /// frame of MobilizedBodyIndex getBodyId(), 0 = Ground). The state is realized to
    /// Stage::Position if it is not already, and geometry of every stage the state has reached is
    /// drawn (Simbody's Visualizer does the same): realize to Dynamics first to include geometry that
    /// force elements emit at Dynamics. Returns a width x height CV_8UC3 BGR image (every render
    /// call: its buffer is reused for the next frame once no cv::Mat refers to it any more, so keep
    /// the cv::Mat, not its data pointer).
    /// Throws InputError for a decoration whose body id is not a body of the system.
    cv::Mat renderFrame(const SimTK::MultibodySystem& system, const SimTK::State& state,
                        const std::vector<SimTK::DecorativeGeometry>& extra = {});

    /// Draws only the given geometry (all bodyId must be 0: there are no bodies to attach it to).
    cv::Mat renderGeometry(const std::vector<SimTK::DecorativeGeometry>& geometry);

    /// Draws a caller-chosen set of decorations placed by the bodies of system in state (realized
    /// to Stage::Position at least; bodyId as in renderFrame), in two layers: `geometry` first, then
    /// `onTop` after clearing the depth buffer, so the second layer is visible through the first
    /// (e.g. a muscle path that runs inside a limb's volume). Use it to select or restyle what a
    /// system emits (collect with calcDecorativeGeometryAndAppend). Throws InputError for a bad
    /// body id and std::logic_error for a state below Stage::Position.
    cv::Mat renderLayers(const SimTK::MultibodySystem& system, const SimTK::State& state,
                         const SimTK::Array_<SimTK::DecorativeGeometry>& geometry,
                         const SimTK::Array_<SimTK::DecorativeGeometry>& onTop = {});

    const RenderSettings& getSettings() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace armsim
