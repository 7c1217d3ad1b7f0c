// SPDX-License-Identifier: MIT
// hello_ode: a terrain from plain arrays, a few bodies dropped on it, the boxtree geom in place of
// dCreateTriMesh. Build against the installed package:
//   find_package(boxtree 0.2 CONFIG REQUIRED COMPONENTS ode)
//   target_link_libraries(hello_ode PRIVATE boxtree::ode)
//! [includes]
#include <boxtree/ode/boxtree_geom.h>
//! [includes]
#include <ode/ode.h>

#include <cmath>
#include <cstdio>
#include <vector>

namespace {

struct World {
  dWorldID world;
  dJointGroupID contacts;
};

double surface(double x, double y) { return 0.5 * std::sin(0.4 * x) * std::cos(0.3 * y); }

void near_callback(void* data, dGeomID a, dGeomID b) {
  auto* w = static_cast<World*>(data);
  dContact contact[8];
  const int count = dCollide(a, b, 8, &contact[0].geom, sizeof(dContact));
  for (int i = 0; i < count; ++i) {
    contact[i].surface.mode = dContactApprox1;
    contact[i].surface.mu = 0.8;
    dJointAttach(dJointCreateContact(w->world, w->contacts, &contact[i]), dGeomGetBody(a), dGeomGetBody(b));
  }
}

}  // namespace

int main() {
  // A 20 m x 20 m rolling terrain, 16 x 16 cells, two triangles per cell, counter-clockwise seen from above (+z).
  const int n = 16;
  const double cell = 20.0 / n;
  std::vector<double> vertices;
  std::vector<dTriIndex> indices;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double x = i * cell - 10, y = j * cell - 10;
      vertices.insert(vertices.end(), {x, y, surface(x, y)});
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const dTriIndex v = j * (n + 1) + i;
      indices.insert(indices.end(), {v, v + 1, v + n + 2, v, v + n + 2, v + n + 1});
    }

  //! [init]
  dInitODE2(0);
  dBoxtreeInit();  // after every dInitODE2 (ODE resets its collider table there)
  //! [init]
  World w{dWorldCreate(), dJointGroupCreate(0)};
  dWorldSetGravity(w.world, 0, 0, -9.81);
  dSpaceID space = dHashSpaceCreate(nullptr);

  //! [swap]
  // The swap: was dGeomTriMeshDataCreate + dGeomTriMeshDataBuildDouble + dCreateTriMesh. The arrays are copied.
  dGeomID terrain = dCreateBoxtreeMesh(space, vertices.data(), 3 * sizeof(double), int(vertices.size() / 3),
                                       indices.data(), int(indices.size()), 3 * sizeof(dTriIndex), "aabb");
  //! [swap]

  std::vector<dBodyID> bodies;
  for (int k = 0; k < 6; ++k) {
    dBodyID body = dBodyCreate(w.world);
    dMass mass;
    dGeomID geom;
    if (k % 3 == 0) {
      geom = dCreateSphere(space, 0.5);
      dMassSetSphereTotal(&mass, 1, 0.5);
    } else if (k % 3 == 1) {
      geom = dCreateBox(space, 0.8, 0.8, 0.8);
      dMassSetBoxTotal(&mass, 1, 0.8, 0.8, 0.8);
    } else {
      geom = dCreateCapsule(space, 0.3, 0.8);
      dMassSetCapsuleTotal(&mass, 1, 3, 0.3, 0.8);
    }
    dBodySetMass(body, &mass);
    dGeomSetBody(geom, body);
    dBodySetPosition(body, -5 + 2 * k, 0.5 * k - 1, 3 + k);
    bodies.push_back(body);
  }

  for (int step = 0; step < 240; ++step) {
    dSpaceCollide(space, &w, near_callback);
    dWorldQuickStep(w.world, 1.0 / 60);
    dJointGroupEmpty(w.contacts);
  }

  // Every body should have landed: its centre above the terrain under it, no longer falling.
  int landed = 0;
  for (dBodyID body : bodies) {
    const dReal* c = dBodyGetPosition(body);
    const double height = c[2] - surface(c[0], c[1]);
    const bool ok = height > 0 && std::abs(dBodyGetLinearVel(body)[2]) < 0.5;
    landed += ok;
    std::printf("body at (%6.2f %6.2f %6.2f), centre %.3f m above the terrain%s\n", c[0], c[1], c[2], height,
                ok ? "" : "  <- has not landed");
  }
  std::printf("hello_ode: %d of %zu bodies landed on the %d-facet boxtree terrain\n", landed, bodies.size(),
              int(indices.size() / 3));

  //! [destroy]
  dGeomDestroy(terrain);
  //! [destroy]
  dSpaceDestroy(space);  // destroys the bodies' geoms too
  dJointGroupDestroy(w.contacts);
  dWorldDestroy(w.world);
  //! [close]
  dBoxtreeClose();  // before dCloseODE
  dCloseODE();
  //! [close]
  return landed == int(bodies.size()) ? 0 : 1;
}
