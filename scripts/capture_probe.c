/* Capture's cost in three shapes of frame, each drawn 5 times (the time of each printed):
 *   tri N    N glBegin/glEnd of one lit triangle each, every frame;
 *   lists N  N small display lists, each called under its own glTranslatef, every frame;
 *   tex 0    a 2048x2048 RGBA texture uploaded with glTexImage2D every frame, on one quad;
 *   ftex 0   the same with a 1024x1024 texture of floats (GL_FLOAT, as scientific data comes);
 *   param 0  the 2048x2048 texture uploaded once, its filters set again (to the same values)
 *            before the quad every frame, as VTK sets a texture's parameters at every render;
 *   sub 0    the 2048x2048 texture uploaded once, a 256x256 part of it replaced with
 *            glTexSubImage2D every frame (a cursor, a moving image).
 *   gcc -O2 -o capture_probe scripts/capture_probe.c -lOSMesa -lm
 *   ./capture_probe tex 0; glray run --set preset=gl --set progressive=false -- ./capture_probe tex 0 */
#include <GL/osmesa.h>
#include <GL/gl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <time.h>
static double now(void) { struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t); return t.tv_sec + t.tv_nsec * 1e-9; }
int main(int argc, char **argv) {
  const char *mode = argv[1]; int n = atoi(argv[2]); int frames = 4;
  int w = 800, h = 600;
  OSMesaContext c = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, NULL);
  unsigned char *buf = malloc(w * h * 4);
  OSMesaMakeCurrent(c, buf, GL_UNSIGNED_BYTE, w, h);
  glMatrixMode(GL_PROJECTION); glFrustum(-1, 1, -0.75, 0.75, 1, 10); glMatrixMode(GL_MODELVIEW);
  glTranslatef(0, 0, -3); glEnable(GL_DEPTH_TEST); glEnable(GL_LIGHTING); glEnable(GL_LIGHT0);
  GLuint base = 0; unsigned char *tex = NULL; int ts = 2048;
  if (!strcmp(mode, "lists")) {
    base = glGenLists(n);
    for (int i = 0; i < n; i++) {
      glNewList(base + i, GL_COMPILE);
      glBegin(GL_TRIANGLES); glNormal3f(0, 0, 1);
      for (int k = 0; k < 12; k++) glVertex3f(0.01f * (k % 3 == 1), 0.01f * (k % 3 == 2), 0.001f * k);
      glEnd(); glEndList();
    }
  }
  int floats = !strcmp(mode, "ftex"), params = !strcmp(mode, "param"), sub = !strcmp(mode, "sub");
  if (params || sub) mode = "tex";
  float *ftex = NULL;
  if (floats) { mode = "tex"; ts = 1024; ftex = malloc(sizeof(float) * ts * ts * 4); }
  if (!strcmp(mode, "tex")) { tex = malloc(ts * ts * 4); glEnable(GL_TEXTURE_2D); glDisable(GL_LIGHTING);
    GLuint t; glGenTextures(1, &t); glBindTexture(GL_TEXTURE_2D, t);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR); }
  for (int f = 0; f <= frames; f++) {
    double t0 = now();
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    if (!strcmp(mode, "tri")) {
      for (int i = 0; i < n; i++) {
        float x = -1 + 2.0f * (i % 1000) / 1000, y = -0.75f + 1.5f * (i / 1000) / (n / 1000 + 1);
        glBegin(GL_TRIANGLES); glNormal3f(0, 0, 1); glVertex3f(x, y, 0); glVertex3f(x + 0.01f, y, 0); glVertex3f(x, y + 0.01f, 0); glEnd();
      }
    } else if (!strcmp(mode, "lists")) {
      for (int i = 0; i < n; i++) {
        glPushMatrix(); glTranslatef(-1 + 2.0f * (i % 100) / 100, -0.75f + 1.5f * (i / 100) / (n / 100 + 1), 0);
        glCallList(base + i); glPopMatrix();
      }
    } else if (!strcmp(mode, "tex")) {
      for (int i = 0; i < ts * ts * 4; i += 4) { tex[i] = (i / 4 + f * 7) & 255; tex[i + 1] = (i / 4096) & 255; tex[i + 2] = 128; tex[i + 3] = 255; }
      if (sub) {
        if (f == 0) glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, ts, ts, 0, GL_RGBA, GL_UNSIGNED_BYTE, tex);
        glTexSubImage2D(GL_TEXTURE_2D, 0, 64 * f, 64 * f, 256, 256, GL_RGBA, GL_UNSIGNED_BYTE, tex);
      } else if (params) {
        if (f == 0) glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, ts, ts, 0, GL_RGBA, GL_UNSIGNED_BYTE, tex);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
      } else if (floats) {
        for (int i = 0; i < ts * ts * 4; i++) ftex[i] = tex[i] / 255.0f;
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, ts, ts, 0, GL_RGBA, GL_FLOAT, ftex);
      } else {
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, ts, ts, 0, GL_RGBA, GL_UNSIGNED_BYTE, tex);
      }
      glBegin(GL_QUADS); glTexCoord2f(0, 0); glVertex2f(-1, -0.75f); glTexCoord2f(1, 0); glVertex2f(1, -0.75f);
      glTexCoord2f(1, 1); glVertex2f(1, 0.75f); glTexCoord2f(0, 1); glVertex2f(-1, 0.75f); glEnd();
    }
    glFinish();
    printf("%s frame %d %.1f ms\n", mode, f, (now() - t0) * 1e3);
  }
  return 0;
}
