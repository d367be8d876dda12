/* An OSMesa program that draws with a 1D texture (glTexImage1D, GL_TEXTURE_1D), as programs
 * colour by a scalar through a colour map: a square whose s runs across it, sampled nearest,
 * then linear with mipmaps on a slanted square (t given but ignored), then with GL_TEXTURE_2D
 * enabled too, which takes precedence. Prints a row of colours for each. Built by
 * tests/raytrace.rs with cc. */
#include "gl_functions.h"

static void square_st(float tilt) {
  glBegin(GL_QUADS);
  glTexCoord2f(0, 0); glVertex3f(-1, -1, -tilt);
  glTexCoord2f(1, 5); glVertex3f(1, -1, tilt);
  glTexCoord2f(1, 9); glVertex3f(1, 1, tilt);
  glTexCoord2f(0, 2); glVertex3f(-1, 1, -tilt);
  glEnd();
}

static void row(const char *name, const unsigned char *buf, int w, int y) {
  printf("%s:", name);
  for (int x = 2; x < w; x += 5) {
    const unsigned char *p = buf + 4 * (w * y + x);
    printf(" %d,%d,%d", p[0], p[1], p[2]);
  }
  printf("\n");
}

int main(void) {
  int w = 64, h = 64;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  /* A colour map of 8 entries, and its mipmaps down to one. */
  unsigned char map[8 * 4];
  for (int i = 0; i < 8; i++) {
    map[4 * i] = (unsigned char)(i * 36);
    map[4 * i + 1] = (unsigned char)(255 - i * 30);
    map[4 * i + 2] = (unsigned char)(i % 2 ? 200 : 40);
    map[4 * i + 3] = 255;
  }
  GLuint tex[2];
  glGenTextures(2, tex);
  glBindTexture(GL_TEXTURE_1D, tex[0]);
  for (int level = 0, n = 8; n >= 1; level++, n /= 2) {
    unsigned char m[8 * 4];
    for (int i = 0; i < n; i++)
      for (int k = 0; k < 4; k++) m[4 * i + k] = map[4 * (i * (8 / n)) + k];
    glTexImage1D(GL_TEXTURE_1D, level, GL_RGBA, n, 0, GL_RGBA, GL_UNSIGNED_BYTE, m);
  }
  glTexParameteri(GL_TEXTURE_1D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_1D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glEnable(GL_TEXTURE_1D);
  glClear(GL_COLOR_BUFFER_BIT);
  square_st(0);
  glFinish();
  row("nearest", buf, w, h / 2);

  glTexParameteri(GL_TEXTURE_1D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  glTexParameteri(GL_TEXTURE_1D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glMatrixMode(GL_PROJECTION);
  glFrustum(-0.5, 0.5, -0.5, 0.5, 1, 10);
  glMatrixMode(GL_MODELVIEW);
  glTranslatef(0, 0, -2.5f);
  glRotatef(70, 0, 1, 0);
  glClear(GL_COLOR_BUFFER_BIT);
  square_st(0);
  glFinish();
  row("linear", buf, w, h / 2);

  /* A white 2D texture bound and enabled as well: it is the one used. */
  unsigned char white[4] = {255, 255, 255, 255};
  glBindTexture(GL_TEXTURE_2D, tex[1]);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, 1, 1, 0, GL_RGBA, GL_UNSIGNED_BYTE, white);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glEnable(GL_TEXTURE_2D);
  glColor3f(0.5f, 0.25f, 1);
  glClear(GL_COLOR_BUFFER_BIT);
  square_st(0);
  glFinish();
  row("both", buf, w, h / 2);
  printf("error 0x%x\n", glGetError());
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
