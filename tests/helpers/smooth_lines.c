/* An OSMesa program that draws antialiased lines (GL_LINE_SMOOTH, two pixels wide) at several
 * slopes and round points (GL_POINT_SMOOTH, six pixels across), blended over black, as
 * gravitywell and boxed do; prints every lit pixel as index:red. Built by tests/raytrace.rs
 * with cc. */
#include <stdio.h>
#include <stdlib.h>

#include "gl_functions.h"

int main(void) {
  int w = 64, h = 64;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  window_projection(w, h);
  glClear(GL_COLOR_BUFFER_BIT);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glEnable(GL_LINE_SMOOTH);
  glLineWidth(2);
  glColor3f(1, 1, 1);
  glBegin(GL_LINES);
  for (int k = 0; k < 4; k++) {
    glVertex2f(2.3f, 4.1f + 9 * k);
    glVertex2f(40.7f, 4.1f + 9 * k + 38.4f * (0.1f + 0.25f * k));
  }
  glVertex2f(50.2f, 2.6f);
  glVertex2f(47.1f, 40.3f);
  glEnd();
  glEnable(GL_POINT_SMOOTH);
  glPointSize(6);
  glBegin(GL_POINTS);
  glVertex2f(52.3f, 52.6f);
  glVertex2f(20.5f, 56.5f);
  glEnd();
  glFinish();
  printf("lit");
  for (int i = 0; i < w * h; i++)
    if (buf[4 * i] > 0)
      printf(" %d:%d", i, buf[4 * i]);
  printf("\n");
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
