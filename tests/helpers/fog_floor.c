/* An OSMesa program with gibson's fog: a white floor under the viewer, from 5 units behind the
 * eye to 60 in front, in linear fog (start 0, end 40) towards black. GL works the fog
 * coordinate out at the vertices, so the part of the floor near the viewer, clipped at the near
 * plane, is fogged by a mix of its corners' distances, not by its own; prints the grey level of
 * the floor at rows from the bottom of the window up to the horizon. Built by tests/raytrace.rs
 * with cc. */
#include <stdio.h>
#include <stdlib.h>

#include "gl_functions.h"

int main(void) {
  int w = 64, h = 64;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  glMatrixMode(GL_PROJECTION);
  glFrustum(-0.1, 0.1, -0.1, 0.1, 0.1, 100);
  glMatrixMode(GL_MODELVIEW);
  glEnable(GL_DEPTH_TEST);
  glEnable(GL_FOG);
  GLfloat black[4] = {0, 0, 0, 1};
  glFogfv(GL_FOG_COLOR, black);
  glFogi(GL_FOG_MODE, GL_LINEAR);
  glFogf(GL_FOG_START, 0);
  glFogf(GL_FOG_END, 40);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glColor3f(1, 1, 1);
  glBegin(GL_QUADS);
  glVertex3f(-20, -1, 5);
  glVertex3f(20, -1, 5);
  glVertex3f(20, -1, -60);
  glVertex3f(-20, -1, -60);
  glEnd();
  glFinish();
  printf("floor");
  for (int y = 0; y < h / 2; y += 4)
    printf(" %d", buf[4 * (w * y + w / 2)]);
  printf("\n");
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
