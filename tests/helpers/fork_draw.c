/* An OSMesa program that draws in a child it forks as well as in itself: a triangle on blue,
 * then glFinish (an OSMesa frame's end), the centre pixel read back and printed, in the parent
 * (red), then in a forked child (green: a new picture, traced in the child), then in the
 * parent again (red). Under glray each of the three
 * frames must be ray traced (the child keeps the parent's ray tracer), and with a trace path
 * holding %p the child records into a trace of its own. Built by tests/raytrace.rs with cc. */
#include <stdio.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <GL/gl.h>
#include <GL/osmesa.h>

static void draw(const char *who, float red, float green) {
  int w = 32, h = 32;
  OSMesaContext c = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, NULL);
  void *buf = malloc(w * h * 4);
  OSMesaMakeCurrent(c, buf, GL_UNSIGNED_BYTE, w, h);
  glViewport(0, 0, w, h);
  glClearColor(0, 0, 1, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glBegin(GL_TRIANGLES);
  glColor3f(red, green, 0);
  glVertex2f(-1, -1); glVertex2f(1, -1); glVertex2f(0, 1);
  glEnd();
  glFinish();
  unsigned char centre[4] = {0}, corner[4] = {0};
  glReadPixels(w / 2, h / 2, 1, 1, GL_RGBA, GL_UNSIGNED_BYTE, centre);
  glReadPixels(0, h - 1, 1, 1, GL_RGBA, GL_UNSIGNED_BYTE, corner);
  printf("%s: centre %d %d %d, corner %d %d %d, error 0x%x\n", who, centre[0], centre[1], centre[2], corner[0],
         corner[1], corner[2], glGetError());
  fflush(stdout);
  OSMesaDestroyContext(c);
  free(buf);
}

int main(void) {
  draw("parent", 1, 0);
  pid_t child = fork();
  if (child == 0) {
    draw("child", 0, 1);
    _exit(0);
  }
  int status = 0;
  waitpid(child, &status, 0);
  draw("parent again", 1, 0);
  return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? 0 : 1;
}
