/* An OSMesa program that makes a texture from its own framebuffer: it draws a picture (red left
 * half, green right half over a blue clear) into the bottom-left 32x32 of its 64x64 buffer and
 * copies it into a texture with glCopyTexImage2D, draws a yellow square into the bottom-left 8x8
 * and copies that into the texture's top-right corner with glCopyTexSubImage2D, then clears the
 * buffer and draws the texture, mirrored left to right, over all of it. It prints the colours
 * at three places and at the end of each step. Under glray the frame so far is ray traced and
 * put in place before each copy, and the texture is read back from the real GL, so the
 * picture is Mesa's. Built by tests/raytrace.rs with cc. */
#include <stdio.h>
#include <stdlib.h>

#include "gl_functions.h"

static void print(const char *what, const unsigned char *buf, int w, int x, int y) {
  const unsigned char *p = buf + 4 * (w * y + x);
  printf("%s %d %d %d\n", what, p[0], p[1], p[2]);
}

int main(void) {
  int w = 64, h = 64;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  GLuint tex;
  glGenTextures(1, &tex);
  glBindTexture(GL_TEXTURE_2D, tex);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);

  glViewport(0, 0, 32, 32);
  glClearColor(0, 0, 1, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glColor3f(1, 0, 0);
  glRectf(-1, -1, 0, 1);
  glColor3f(0, 1, 0);
  glRectf(0, -1, 1, 1);
  glCopyTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, 0, 0, 32, 32, 0);

  glClearColor(0, 0, 0, 1);
  glClear(GL_COLOR_BUFFER_BIT);
  glViewport(0, 0, 8, 8);
  glColor3f(1, 1, 0);
  glRectf(-1, -1, 1, 1);
  glCopyTexSubImage2D(GL_TEXTURE_2D, 0, 24, 24, 0, 0, 8, 8);

  glViewport(0, 0, w, h);
  glClear(GL_COLOR_BUFFER_BIT);
  glEnable(GL_TEXTURE_2D);
  glColor3f(1, 1, 1);
  glBegin(GL_QUADS);
  glTexCoord2f(1, 0);
  glVertex2f(-1, -1);
  glTexCoord2f(0, 0);
  glVertex2f(1, -1);
  glTexCoord2f(0, 1);
  glVertex2f(1, 1);
  glTexCoord2f(1, 1);
  glVertex2f(-1, 1);
  glEnd();
  glDisable(GL_TEXTURE_2D);
  glFinish();
  /* The copy's right half (green) on the left, its left half (red) on the right, the square in
   * the top left. */
  print("left", buf, w, 8, 32);
  print("right", buf, w, 56, 8);
  print("corner", buf, w, 8, 56);
  /* A copy of depth into a depth texture: capture keeps no depth textures, and reading it back
   * as colour would raise an error the program never caused. */
  GLuint depth;
  glGenTextures(1, &depth);
  glBindTexture(GL_TEXTURE_2D, depth);
  glCopyTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT, 0, 0, 16, 16, 0);
  printf("error 0x%x\n", glGetError());
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
