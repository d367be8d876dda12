/* An OSMesa program that draws two views side by side in one window, as antmaze (three) and
 * multi-view layouts do: the left half through a perspective camera (a red square), the right
 * half through an orthographic one (a green square), each in its own glViewport; the window
 * cleared once, then the right half again to grey within a scissor box. Then, in a small third viewport over the top right corner, a blue square with no
 * depth clear: its fragments are depth tested against the green square's. Prints the colours
 * at the centre of each half, where the blue square lies behind the green one, and where it
 * covers the background. Built by tests/raytrace.rs with cc. */
#include <stdio.h>
#include <stdlib.h>

#include "gl_functions.h"

int main(void) {
  int w = 64, h = 32;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  glEnable(GL_DEPTH_TEST);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);

  glViewport(0, 0, 32, 32);
  glMatrixMode(GL_PROJECTION);
  glLoadIdentity();
  glFrustum(-1, 1, -1, 1, 1, 10);
  glMatrixMode(GL_MODELVIEW);
  glLoadIdentity();
  glColor3f(1, 0, 0);
  square(1, -3);

  /* The right view clears its own part to dark grey, as each view of a layout does. */
  glViewport(32, 0, 32, 32);
  glEnable(GL_SCISSOR_TEST);
  glScissor(32, 0, 32, 32);
  glClearColor(0.25f, 0.25f, 0.25f, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glDisable(GL_SCISSOR_TEST);
  glMatrixMode(GL_PROJECTION);
  glLoadIdentity();
  glOrtho(-2, 2, -2, 2, -5, 5);
  glMatrixMode(GL_MODELVIEW);
  glColor3f(0, 1, 0);
  square(1, 0);

  /* Over the green square's top right corner, tilted away from the viewer on its left: where
   * it overlaps the green square it lies behind it and the depth test keeps green; to its right
   * it covers the background. */
  glViewport(48, 16, 16, 16);
  glRotatef(-60, 0, 1, 0);
  glColor3f(0, 0, 1);
  square(2, 0);
  glFinish();

  const unsigned char *left = buf + 4 * (w * 16 + 16), *right = buf + 4 * (w * 8 + 44);
  const unsigned char *left_bg = buf + 4 * (w * 2 + 2), *right_bg = buf + 4 * (w * 2 + 34);
  const unsigned char *behind = buf + 4 * (w * 20 + 53), *over = buf + 4 * (w * 20 + 58);
  printf("left %d %d %d right %d %d %d behind %d %d %d over %d %d %d backgrounds %d %d\n", left[0], left[1], left[2],
         right[0], right[1], right[2], behind[0], behind[1], behind[2], over[0], over[1], over[2], left_bg[0],
         right_bg[0]);
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
