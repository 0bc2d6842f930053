// Display: what the image shows of an environment's solution. Every leaf
// element (element.h) of every patch is drawn as one piece whose corner
// radiance is the nodal average of the leaves around that corner: at a
// patch's own corners, the shared lattice vertex (Environment::
// ComputeVertexRadiosity, which averages across the patches of a polygon);
// elsewhere, the area-weighted mean of the patch's leaves that touch it.
// Back faces are black.
#pragma once

#include "vismask/camera.h"
#include "vismask/environment.h"
#include "vismask/raster.h"

namespace vismask {

// Draws environment `env`'s leaves into `fb`, with `ambient` (Cohen's term,
// per channel) added as kd * ambient. Updates env's vertex radiosity.
// Allocates nothing.
void DrawEnvironment(const View& view, Environment* env, const double ambient[3], Framebuffer* fb);

}  // namespace vismask
