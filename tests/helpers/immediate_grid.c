/* An OSMesa program that draws a big lit surface in immediate mode, as old visualization
 * programs do every frame: glBegin, then glColor4ubv/glNormal3fv/glVertex3fv per corner, glEnd.
 *   0: a wavy 80 x 80 grid as one glBegin(GL_TRIANGLES) (37,446 vertices);
 *   1: the same calls again;
 *   2: the same grid with a band raised and half its colours changed;
 *   3: frame 2 with glMaterialfv (an emission) given halfway through the glBegin;
 *   4: the grid as one glBegin(GL_QUADS) under a local light, so that the diagonal each quad
 *      is cut along shows;
 *   5: frame 2 with GL_LIGHTING off;
 *   6, 7: unlit, four big quads with a different colour at each corner, then 1,100 quads shrunk
 *      to a point to make the glBegin long: in frame 6 that point is outside the view volume,
 *      and Mesa cuts every quad of the glBegin along the other diagonal (its clipping path
 *      cuts quads as an indexed draw does), which shows in the colours between the corners.
 * glray records such a glBegin as a mesh, drawn as an instance and kept by what it gives:
 * frame 1 reuses frame 0's mesh, frame 2 must not, and frame 3's glMaterial sends the glBegin
 * back through the vertex stage. Prints an 8 x 8 grid of pixels per frame, and the current
 * normal and colour after the last glEnd. Built by tests/raytrace.rs with cc. */
#include <math.h>

#include "gl_functions.h"
#include "wavy_grid.h"

static void corner(int k) {
  glColor4ubv(col + 4 * k);
  glNormal3fv(nrm + 3 * k);
  glVertex3fv(pos + 3 * k);
}

/* The grid's cells as triangles (material: give an emission halfway through) or quads. */
static void draw_grid(int quads, int material) {
  const GLfloat glow[4] = {0.5f, 0.1f, 0.1f, 1};
  glBegin(quads ? GL_QUADS : GL_TRIANGLES);
  for (int j = 0; j + 1 < N; j++) {
    if (material && j == N / 2) glMaterialfv(GL_FRONT_AND_BACK, GL_EMISSION, glow);
    for (int i = 0; i + 1 < N; i++) {
      int k = j * N + i;
      if (quads) {
        corner(k), corner(k + 1), corner(k + N + 1), corner(k + N);
      } else {
        corner(k), corner(k + 1), corner(k + N + 1);
        corner(k), corner(k + N + 1), corner(k + N);
      }
    }
  }
  glEnd();
  if (material) {
    const GLfloat none[4] = {0, 0, 0, 1};
    glMaterialfv(GL_FRONT_AND_BACK, GL_EMISSION, none);
  }
}

/* Four quads over the window, and `pad` quads shrunk to a point at x = at. */
static void draw_color_quads(int pad, float at) {
  static const unsigned char c[4][3] = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {255, 255, 255}};
  glBegin(GL_QUADS);
  for (int q = 0; q < 4; q++) {
    float x = -0.9f + 0.9f * (q % 2), y = -0.9f + 0.9f * (q / 2);
    float corners[4][2] = {{x, y}, {x + 0.85f, y}, {x + 0.85f, y + 0.85f}, {x, y + 0.85f}};
    for (int k = 0; k < 4; k++) glColor3ubv(c[(k + q) % 4]), glVertex3f(corners[k][0], corners[k][1], 0);
  }
  for (int k = 0; k < 4 * pad; k++) glVertex3f(at, 0, 0);
  glEnd();
}

int main(void) {
  int w = 96, h = 96;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  view_grid();

  for (int f = 0; f < 8; f++) {
    make_grid(f >= 2 ? 0.2f : 0);
    if (f >= 2)
      for (int k = 0; k < N * N / 2; k++) col[4 * k + 2] = 20;
    if (f == 4) {
      GLfloat near[4] = {0.2f, 0.4f, 0.6f, 1};
      glLightfv(GL_LIGHT0, GL_POSITION, near);
    }
    if (f == 5) glDisable(GL_LIGHTING);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    if (f >= 6) {
      glPushMatrix(), glLoadIdentity(), glTranslatef(0, 0, -3);
      draw_color_quads(1100, f == 6 ? 50.0f : 0.0f);
      glPopMatrix();
    } else {
      draw_grid(f == 4, f == 3);
    }
    glFinish();
    print_frame(f, buf, w, h);
  }
  GLfloat n[4], col4[4];
  glGetFloatv(GL_CURRENT_NORMAL, n);
  glGetFloatv(GL_CURRENT_COLOR, col4);
  printf("current normal %.3f %.3f %.3f color %.3f %.3f %.3f %.3f\n", n[0], n[1], n[2], col4[0], col4[1], col4[2],
         col4[3]);
  printf("error 0x%x\n", glGetError());
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
