/* An OSMesa program that draws one lit-free, smooth-shaded triangle with depth testing and reads
 * the frame back with glReadPixels as DEPTH_COMPONENT (float and unsigned int) and RGB bytes,
 * printing a few pixels: under glray the read must return the ray-traced frame, with Mesa's
 * depth values. Built by tests/raytrace.rs with cc. */
#include <GL/osmesa.h>
#include <GL/gl.h>
#include <stdio.h>
#include <stdlib.h>
int main(void) {
  int w = 64, h = 64;
  OSMesaContext c = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, NULL);
  void *buf = malloc(w * h * 4);
  OSMesaMakeCurrent(c, buf, GL_UNSIGNED_BYTE, w, h);
  glViewport(0, 0, w, h);
  glMatrixMode(GL_PROJECTION); glLoadIdentity(); glFrustum(-1, 1, -1, 1, 1, 10);
  glMatrixMode(GL_MODELVIEW); glLoadIdentity();
  glEnable(GL_DEPTH_TEST);
  glClearColor(0.1, 0.2, 0.3, 1); glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glBegin(GL_TRIANGLES);
  glColor3f(1, 0, 0); glVertex3f(-2, -2, -3); glColor3f(0, 1, 0); glVertex3f(2, -2, -5); glColor3f(0, 0, 1); glVertex3f(0, 2, -4);
  glEnd();
  float depth[64 * 64]; unsigned char rgb[64 * 64 * 3]; unsigned int udepth[64 * 64];
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, depth);
  glReadPixels(0, 0, w, h, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, udepth);
  glReadPixels(0, 0, w, h, GL_RGB, GL_UNSIGNED_BYTE, rgb);
  int pts[][2] = {{32, 32}, {10, 10}, {50, 20}, {32, 50}, {0, 63}};
  for (int i = 0; i < 5; i++) {
    int x = pts[i][0], y = pts[i][1], k = y * w + x;
    printf("(%d,%d) depth %.5f u %u rgb %d %d %d\n", x, y, depth[k], udepth[k] >> 16, rgb[3*k], rgb[3*k+1], rgb[3*k+2]);
  }
  return 0;
}
