/* An OSMesa program that draws aliased lines three pixels wide at several slopes, in an
 * orthographic window-sized projection, and prints the index of every pixel they light. GL
 * widens an aliased line along its minor axis (a parallelogram three pixels tall for an
 * x-major line), not across it. Built by tests/raytrace.rs with cc. */
#include <stdio.h>
#include <stdlib.h>

#include "gl_functions.h"

int main(void) {
  int w = 64, h = 64;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  window_projection(w, h);
  glClear(GL_COLOR_BUFFER_BIT);
  glColor3f(1, 1, 1);
  glLineWidth(3);
  glBegin(GL_LINES);
  /* x-major at slopes 0.3 to 0.9, and y-major ones. */
  for (int k = 0; k < 4; k++) {
    glVertex2f(2.3f, 4.1f + 12 * k);
    glVertex2f(30.7f, 4.1f + 12 * k + 28.4f * (0.3f + 0.2f * k));
    glVertex2f(36.2f + 6 * k, 2.2f);
    glVertex2f(36.2f + 6 * k + 20.5f * (0.3f + 0.2f * k), 60.3f);
  }
  glEnd();
  glFinish();
  printf("lit");
  for (int i = 0; i < w * h; i++)
    if (buf[4 * i] > 128)
      printf(" %d", i);
  printf("\n");
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
