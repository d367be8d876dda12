/* An OSMesa program that draws a transparent shell the way xscreensaver's molecule does, from
 * display lists:
 *   - list 1, the model: a glTranslatef outside any push and pop, then a red square. After
 *     calling it the program reads the modelview back (glGetFloatv), as molecule does to place
 *     its labels, and prints the translation: the real GL has it only if it ran the list or was
 *     given the list's matrix afterwards.
 *   - list 2, the shell: a bigger square in front. First drawn with every colour channel masked
 *     (depth only), then again with glDepthFunc(GL_EQUAL) and blending, so that only its nearest
 *     surface is blended over the model, half transparent.
 * A glClear of the colour buffer with every channel masked sits between the two: GL leaves the
 * colour buffer alone. Prints the colour at the centre (model under shell) and at a corner of
 * the shell (shell over the background). Built by tests/raytrace.rs with cc. */
#include <stdio.h>
#include <stdlib.h>

#include "gl_functions.h"

int main(void) {
  int w = 64, h = 64;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  glMatrixMode(GL_PROJECTION);
  glFrustum(-1, 1, -1, 1, 1, 20);
  glMatrixMode(GL_MODELVIEW);
  glTranslatef(0, 0, -3);
  glNewList(1, GL_COMPILE);
  glTranslatef(0.25f, 0, 0);
  square(0.5f, 0);
  glEndList();
  glNewList(2, GL_COMPILE);
  square(1.5f, 1);
  glEndList();

  glEnable(GL_DEPTH_TEST);
  glClearColor(0, 0, 0, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glPushMatrix();
  glColor3f(1, 0, 0);
  glCallList(1);
  float m[16];
  glGetFloatv(GL_MODELVIEW_MATRIX, m);
  glPopMatrix();

  glColorMask(0, 0, 0, 0);
  glClear(GL_COLOR_BUFFER_BIT);
  glCallList(2);
  glColorMask(1, 1, 1, 1);
  glDepthFunc(GL_EQUAL);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glColor4f(0, 0, 1, 0.5f);
  glCallList(2);
  glFinish();

  const unsigned char *centre = buf + 4 * (w * (h / 2) + w / 2 + 4);
  const unsigned char *corner = buf + 4 * (w * (h / 2 + 20) + w / 2 - 20);
  printf("centre %d %d %d corner %d %d %d modelview %.4f %.4f %.4f error 0x%x\n", centre[0], centre[1],
         centre[2], corner[0], corner[1], corner[2], m[12], m[13], m[14], glGetError());
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
