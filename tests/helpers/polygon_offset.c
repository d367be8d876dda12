/* An OSMesa program that draws hidden-line style: a filled red square pushed back with
 * glPolygonOffset(1, 1) (GL_POLYGON_OFFSET_FILL), then white lines in the same plane, depth
 * tested with GL_LESS. The offset is what lets the lines win over the fill they lie on; it
 * prints how many pixels are white and how many red. Built by tests/raytrace.rs with cc. */
#include <stdio.h>
#include <stdlib.h>

#include "gl_functions.h"

int main(void) {
  int w = 64, h = 64;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  glEnable(GL_DEPTH_TEST);
  glMatrixMode(GL_PROJECTION);
  glFrustum(-1, 1, -1, 1, 1, 20);
  glMatrixMode(GL_MODELVIEW);
  glTranslatef(0, 0, -3);
  glRotatef(50, 1, 0.3f, 0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(1, 1);
  glColor3f(1, 0, 0);
  glBegin(GL_QUADS);
  glVertex3f(-1, -1, 0);
  glVertex3f(1, -1, 0);
  glVertex3f(1, 1, 0);
  glVertex3f(-1, 1, 0);
  glEnd();
  glDisable(GL_POLYGON_OFFSET_FILL);
  glColor3f(1, 1, 1);
  glBegin(GL_LINES);
  for (int i = -4; i <= 4; i++) {
    glVertex3f(i * 0.2f, -1, 0);
    glVertex3f(i * 0.2f, 1, 0);
  }
  glEnd();
  glFinish();
  int white = 0, red = 0;
  for (int i = 0; i < w * h; i++) {
    const unsigned char *p = buf + 4 * i;
    if (p[0] > 200 && p[1] > 200)
      white++;
    else if (p[0] > 200)
      red++;
  }
  printf("white %d red %d\n", white, red);
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
