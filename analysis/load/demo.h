// Scenes generated in code: the built-in demo (`visaudit analyze` with no scene) and the mesh
// primitives it and the tests are made of.
#pragma once

#include "analysis/scene.h"

namespace va {

// Primitive meshes, front faces counter-clockwise seen from outside.
RawMesh boxMesh(Vec3 center, Vec3 halfExtent);
RawMesh uvSphereMesh(Vec3 center, double radius, int segments, int bands);
// A w x h grid of quads (2 triangles each) on the plane spanned by axes u and v through origin,
// front face towards u x v.
RawMesh gridMesh(Vec3 origin, Vec3 u, Vec3 v, int w, int h);

// The built-in demo scene. It exercises every stage: objects off-screen and behind the eye
// (frustum), a closed box and sphere (backface: about half their triangles face away), a wall
// crossing the near plane (clip), a double-sided banner seen from its back (exempt from backface),
// a decal coplanar with the floor (z-fighting), and two views.
SceneBuildInput demoSceneInput();
Scene demoScene();

}  // namespace va
