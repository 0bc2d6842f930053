// Camera: a pinhole looking from `eye` at `target`. The default frames a
// scene's bounding box from its -z side looking +z (the Cornell box's
// original camera).
#pragma once
#include <glm/vec3.hpp>

#include "vismask/scene.h"

namespace vismask {

struct Camera {
  glm::vec3 eye{0.0f, 0.0f, -1.0f};
  glm::vec3 target{0.0f};
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  float fovyDeg = 39.3f;
};

// The default camera for `bounds`: centred on the box in x and y, far enough
// back on -z that the box's front face fills the vertical field of view with
// a 4% margin, looking +z, up +y.
Camera DefaultCamera(const Bounds& bounds);

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

}  // namespace vismask
