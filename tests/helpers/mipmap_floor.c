/* An OSMesa program with a mipmapped texture on a floor seen at a grazing angle: each level a
 * colour of its own (GL_NEAREST_MIPMAP_NEAREST), so the picture shows which level each pixel
 * took. GL picks the level per pixel (per 2x2 quad), from how fast the texture coordinates
 * change there: near the viewer level 0, farther away ever coarser ones. Prints, for rows from
 * the bottom of the window to the horizon, the level the centre pixel shows. Built by
 * tests/raytrace.rs with cc. */
#include <stdio.h>
#include <stdlib.h>

#include "gl_functions.h"

static const unsigned char level_colors[7][3] = {
    {255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {255, 255, 0}, {0, 255, 255}, {255, 0, 255}, {255, 255, 255}};

int main(void) {
  int w = 64, h = 64;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  static unsigned char texels[64 * 64 * 3];
  for (int level = 0, size = 64; size >= 1; level++, size /= 2) {
    for (int i = 0; i < size * size; i++)
      for (int k = 0; k < 3; k++)
        texels[3 * i + k] = level_colors[level][k];
    glTexImage2D(GL_TEXTURE_2D, level, GL_RGB, size, size, 0, GL_RGB, GL_UNSIGNED_BYTE, texels);
  }
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST_MIPMAP_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexEnvi(GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_REPLACE);
  glEnable(GL_TEXTURE_2D);
  glMatrixMode(GL_PROJECTION);
  glFrustum(-0.1, 0.1, -0.1, 0.1, 0.1, 100);
  glMatrixMode(GL_MODELVIEW);
  glClear(GL_COLOR_BUFFER_BIT);
  glBegin(GL_QUADS);
  glTexCoord2f(0, 0);
  glVertex3f(-10, -1, -0.5f);
  glTexCoord2f(4, 0);
  glVertex3f(10, -1, -0.5f);
  glTexCoord2f(4, 40);
  glVertex3f(10, -1, -80);
  glTexCoord2f(0, 40);
  glVertex3f(-10, -1, -80);
  glEnd();
  glFinish();
  printf("levels");
  for (int y = 0; y < h / 2 - 2; y += 2) {
    const unsigned char *p = buf + 4 * (w * y + w / 2);
    int level = -1;
    for (int l = 0; l < 7; l++)
      if (abs(p[0] - level_colors[l][0]) < 8 && abs(p[1] - level_colors[l][1]) < 8 && abs(p[2] - level_colors[l][2]) < 8)
        level = l;
    printf(" %d", level);
  }
  printf("\n");
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
