// Camera: a pinhole looking from `eye` at `target`. Without --camera the
// camera frames the scene's bounding box from one of its six sides (--view,
// or the side chosen by ChooseViewSide).
#pragma once
#include <cstdint>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <vector>

#include "vismask/scene/scene.h"
#include "vismask/solve/outside.h"

namespace vismask {

struct Camera {
  glm::vec3 eye{0.0f, 0.0f, -1.0f};
  glm::vec3 target{0.0f};
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  float fovyDeg = 39.3f;
};

// The side of the bounding box the eye is on. front is the Cornell box's
// original camera (-z side, looking +z, up +y), whose image has +x on the
// left; left and right are named as in that image: left is the +x side,
// right the -x side; the four horizontal views have up +y. top (+y side)
// and bottom (-y side) are the front camera turned about x over the box and
// under it: up is +z and -z, and +x stays on the image's left.
enum class ViewSide : uint8_t { kFront, kBack, kLeft, kRight, kTop, kBottom };
constexpr int kNumViewSides = 6;

// "front", "back", "left", "right", "top", "bottom".
const char* ViewSideName(ViewSide side);
// The side named `name` (as ViewSideName spells it); false for any other.
bool ParseViewSide(const char* name, ViewSide* side);

// The camera for `side` of `bounds`: looking along the axis through the
// box's centre at the face on that side, far enough back that the face's
// larger extent fills the vertical field of view (39.3 degrees) with a 4%
// margin. kFront is the camera vismask always used before --view.
Camera SideCamera(const Bounds& bounds, ViewSide side);

// SideCamera(bounds, ViewSide::kFront).
Camera DefaultCamera(const Bounds& bounds);

// How much of each side's image shows the front of a polygon: the rays, out
// of kViewProbeRays^2 through the image's pixel centres (a square image),
// whose nearest hit is a polygon's front side. Occlusion counts: a ray that
// meets the back of a wall first sees nothing, whatever lies beyond. Indexed
// by ViewSide. Deterministic (no random numbers), init-time (heap allowed);
// each ray tests only the polygons whose projected bounds hold it.
constexpr int kViewProbeRays = 64;
void VisibleFrontRays(const Scene& scene, uint32_t rays[kNumViewSides]);

// The default camera's side: the one whose image shows the most front-facing
// surface (VisibleFrontRays), a side within 1% of the best count counting
// as tied with it, ties going to the first of front, back, left, right,
// top, bottom. From outside, a polygon facing into the box shows its back,
// so an open box is seen through its open side (the Cornell box from -z,
// McGuire's CornellBox-Sphere from +z); a box closed on every side shows no
// front from anywhere and keeps front.
ViewSide ChooseViewSide(const Scene& scene);

// Inside views (issue 40): where the outside views see mostly back faces or
// one wall (a closed room, a building, a box whose walls face in), the
// default camera goes inside. Candidate k (0 to kInsideCandidates - 1)
// stands at 60% of the box's height over one of the 8 points (0.15, 0.5,
// 0.85 of x and z but the centre) and looks across the middle at the
// mirrored point at 35% of the height, up +y, 70 degrees; the candidates'
// images are probed as the sides' are (kInsideProbeRays^2 rays) and the one
// with the most front hits off the orientation most of them share wins
// (a view across a room, not of one wall or a block up close), ties to the
// first.
constexpr int kInsideCandidates = 8;
constexpr int kInsideProbeRays = 32;
Camera InsideCamera(const Bounds& bounds, int candidate);

// The inside candidates scored by how lit they are: each front hit of a
// candidate's probe weighted by an estimate, at init and before the solve,
// of the irradiance there from the scene's brightest emitters (up to
// kViewLights, by power): each a small Lambertian source at its polygon's
// centre, E = power cos(at the lamp) cos(at the surface) / (pi r^2), seen
// or not through a shadow map probed from the lamp (kLightProbeRays^2 rays
// over 120 degrees about its normal; a point outside that cone counts as
// unlit). The lit score is the geometric one (front hits off their
// commonest orientation) with each hit counted by that estimate.
struct ViewLight {
  glm::vec3 centre{0.0f}, normal{0.0f, 1.0f, 0.0f};
  double power = 0.0;  // Ke * area, the channels' mean
};
constexpr int kViewLights = 4;
constexpr int kLightProbeRays = 32;

// Light from outside counts too (--sky, --sun; outside.h), each as light
// along fixed directions seen through shadow maps taken from far outside
// the box (kSunProbeRays^2 rays over the box for the sun, whose light
// makes sharp patches, kOutsideProbeRays^2 for each sky direction; the eye
// 8 box diagonals away, so that its rays run within 4 degrees of the
// direction): the sun gives E max(0, n.s) where its map sees x (E the
// channels' mean; its angular diameter left out); the sky, kViewSkyDirections directions w
// (the 26 from a cube's centre to its faces', edges' and corners' centres),
// the sum of L(w) max(0, n.w) W over those whose map sees x, L the uniform
// sky's radiance or the map's along w (the channels' mean), W the weight
// that gives a plane facing an axis, open to the sky, pi L.
constexpr int kViewSkyDirections = 26;
constexpr int kOutsideProbeRays = 32;
constexpr int kSunProbeRays = 96;

// What the probe chose: the best side, how its image fares (the share of
// its rays whose nearest hit is a front face, of those that hit a back face,
// and whether one plane's orientation holds 90% of its front hits), and
// whether an inside candidate replaces it (`inside`, `candidate`, its
// front share). The side's image is poor when back hits outnumber front
// hits or it shows one wall; an inside candidate then wins when its front
// share is larger than the side's and at least 1/2, and at least a tenth of
// its front hits are off their commonest orientation.
struct ViewChoice {
  ViewSide side = ViewSide::kFront;
  double sideFront = 0.0, sideBack = 0.0;
  bool sideOneWall = false;
  bool inside = false;
  int candidate = -1;           // the best inside candidate probed (-1: none)
  double candidateFront = 0.0;  // its front share
  double candidateScore = 0.0;  // its share of front hits off their commonest orientation
  // Every candidate's scores (-1: not probed): the geometric one (as
  // candidateScore) and the lit one (ViewLight; 0 without lights). With
  // lights, the candidate is the one of highest lit score of those that
  // would go inside (front share above the side's and at least 1/2, a
  // tenth of it off the commonest orientation); without, or where no lit
  // score is above 0, the highest geometric score (`byLight` false).
  double geometric[kInsideCandidates] = {};
  double lit[kInsideCandidates] = {};
  bool byLight = false;
  // What the lit scores count: the lamps (ViewLight), the sun, the sky.
  int lamps = 0;
  bool sun = false, sky = false;
};

// A camera's derived basis for projection onto a width x height image.
struct View {
  glm::vec3 eye, right, up, forward;  // right is image +x, up is image +y
  float focal;                        // pixels: (height / 2) / tan(fovy / 2)
  float nearZ;                        // near clipping distance: 1e-3 * |target - eye|
  int width, height;
};

// False if the camera is degenerate (eye == target, up parallel to the view
// direction, fov outside (0, 180)).
bool MakeView(const Camera& camera, int width, int height, View* view);

// ChooseViewSide fed one polygon at a time, in file order, once the scene's
// bounds are known (the streaming loader's later pass, scene_stream.h): it
// holds per probe ray the nearest hit so far, never the polygons, and gives
// the same counts and side as the near-to-far sweep over the whole scene
// (of polygons a ray meets at one depth, the one with the nearer corner,
// then the earlier in the file, is seen). Init-time (heap: HeapBytes()).
class ViewProbe {
 public:
  explicit ViewProbe(const Bounds& bounds);
  // `twoSided`: the polygon shows both sides (--two-sided, a doubleSided
  // glTF material); the inside candidates count its back as a front (the
  // sides keep their counts of old).
  void Add(uint32_t index, const Polygon& polygon, bool twoSided = false);
  // The lamps the lit score estimates light from (at most kViewLights
  // taken), before the first Add.
  void SetLights(const std::vector<ViewLight>& lights);
  // The light from outside the lit score estimates too (--sky, --sun:
  // kViewSkyDirections; a sky map's radiance along them is read here),
  // before the first Add.
  void SetOutside(const OutsideLight& light);
  void Rays(uint32_t rays[kNumViewSides]) const;  // as VisibleFrontRays
  ViewSide Side() const;                          // as ChooseViewSide
  // The side, and whether an inside candidate replaces it (ViewChoice).
  ViewChoice Choose() const;
  // The heap the probe holds at most, its outside light's shadow maps included.
  static uint64_t HeapBytes(const OutsideLight& light);

 private:
  struct Probe {
    bool ok = false;
    View view;
    std::vector<glm::dvec3> dir;
    std::vector<double> depth, nearest;
    std::vector<uint32_t> index;
    std::vector<uint8_t> front;
    std::vector<uint8_t> plane;     // the hit's orientation: 1 + 2 * axis + (normal < 0); 0: none
    std::vector<glm::vec3> normal;  // the hit polygon's normal
    int n = kViewProbeRays;
    // Where x falls in this probe's image (*sx, *sy in pixels from the top
    // left; outside [0, n) beyond it), and *d = x - eye; false when x is
    // not in front of the eye.
    bool Project(const glm::dvec3& x, glm::dvec3* d, double* sx, double* sy) const;
  };
  void Start(Probe& probe, const Camera& camera, int n);
  // The estimated irradiance at x (normal n, facing the viewer) from the lights.
  double LightAt(const glm::dvec3& x, const glm::dvec3& n) const;
  // The same from the sun and the sky (camera_outside.cpp), at x on
  // polygon `polygon` (its index in Add).
  double OutsideAt(const glm::dvec3& x, const glm::dvec3& n, uint32_t polygon) const;
  // The share (0 to 1) of x on `polygon` the far shadow map `probe` sees
  // (nothing nearer its eye).
  double FarSeen(const Probe& probe, const glm::dvec3& x, uint32_t polygon) const;
  void AddTo(Probe& probe, uint32_t index, const Polygon& p, bool clip, bool twoSided);
  Probe probes_[kNumViewSides];
  Probe inside_[kInsideCandidates];
  ViewLight lights_[kViewLights];
  Probe lightProbes_[kViewLights];  // from each lamp along its normal: its shadow map
  int numLights_ = 0;
  // The sun's irradiance (0: none) and direction towards it, and its map.
  double sun_ = 0.0;
  glm::dvec3 sunToward_{0.0, 1.0, 0.0};
  Probe sunProbe_;
  // Each sky direction's radiance times its weight (0: no sky), and its map.
  double sky_[kViewSkyDirections] = {};
  glm::dvec3 skyDir_[kViewSkyDirections];
  Probe skyProbes_[kViewSkyDirections];
  bool hasSky_ = false;
  float reach_ = 0.0f;  // the box's diagonal
  glm::vec3 centre_{0.0f};
  std::vector<glm::dvec2> poly_;
};

}  // namespace vismask
