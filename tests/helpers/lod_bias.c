/* An OSMesa program that draws a mipmapped texture (level 0 white, the smaller levels black)
 * one texel to a pixel, where the level of detail is 0, with GL_TEXTURE_LOD_BIAS (as
 * xscreensaver's texture fonts soften their glyphs with 0.25), then with GL_TEXTURE_MIN_LOD.
 * Prints the colour at the centre of each. Built by tests/raytrace.rs with cc. */
#include "gl_functions.h"
#include <string.h>

#define GL_TEXTURE_LOD_BIAS 0x8501

static void draw(int w, int h) {
  glClear(GL_COLOR_BUFFER_BIT);
  glBegin(GL_QUADS);
  glTexCoord2f(0, 0); glVertex2f(0, 0);
  glTexCoord2f(1, 0); glVertex2f(w, 0);
  glTexCoord2f(1, 1); glVertex2f(w, h);
  glTexCoord2f(0, 1); glVertex2f(0, h);
  glEnd();
  glFinish();
}

static void report(const char *name, int w, int h, const unsigned char *buf) {
  const unsigned char *p = buf + 4 * (w * (h / 2) + w / 2);
  printf("%s %d %d %d\n", name, p[0], p[1], p[2]);
}

int main(void) {
  int w = 64, h = 64;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  window_projection(w, h);
  static unsigned char texels[64 * 64 * 4];
  glEnable(GL_TEXTURE_2D);
  glTexEnvi(GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_REPLACE);
  for (int level = 0, size = 64; size >= 1; level++, size /= 2) {
    memset(texels, level == 0 ? 255 : 0, sizeof texels);
    glTexImage2D(GL_TEXTURE_2D, level, GL_RGBA, size, size, 0, GL_RGBA, GL_UNSIGNED_BYTE, texels);
  }
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  draw(w, h);
  report("plain", w, h, buf);
  glTexParameterf(GL_TEXTURE_2D, GL_TEXTURE_LOD_BIAS, 0.25f);
  draw(w, h);
  report("bias", w, h, buf);
  glTexParameterf(GL_TEXTURE_2D, GL_TEXTURE_LOD_BIAS, 0.0f);
  glTexParameterf(GL_TEXTURE_2D, GL_TEXTURE_MIN_LOD, 1.0f);
  draw(w, h);
  report("min-lod", w, h, buf);
  printf("error 0x%x\n", glGetError());
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
