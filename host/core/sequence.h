/*
 * A sequence of frames: the same scene baked at frame times F (A, A + STEP, ... up to B), each into
 * its own file named by a printf pattern (name.%04d.exr); every layer whose class has a "time" key
 * is set to F (a flame's keyframes, as flam3-animate's begin, end and dtime select them). A frame is
 * a bake like any other (its stored scene says its time), so a frame baked alone is the same file as
 * the same frame of the whole sequence, and a sequence resumed skips the frames already there.
 */
#ifndef FB_SEQUENCE_H
#define FB_SEQUENCE_H

#include "scene.h"

typedef struct fb_frames {
    long first, last, step; /* first, first + step, ... while <= last */
} fb_frames;

/* Reads "A-B", "A-B:STEP" or "A" (what: the flag or key, for messages); A <= B, STEP >= 1; A and B
 * may be negative ("-3--1"). Errors: FB_ERR_USAGE with one line. */
fb_result fb_frames_parse(const char *what, const char *text, fb_frames *out);

/* The number of frames. */
long fb_frames_count(const fb_frames *f);

/* The scene key "frames" of s: *has false where it is not given. Errors: as fb_frames_parse. */
fb_result fb_scene_frames(const fb_scene *s, bool *has, fb_frames *out);

/* Task k of n's share of the frames (render --task K/N, `plan`): the frames of index [*i0, *i1)
 * (frame first + i * step), in order, as even as whole frames allow. */
void fb_frames_share(const fb_frames *f, int k, int n, long *i0, long *i1);

/* Whether path has a frame pattern: exactly one %d or %0Nd (N 1 to 9) and no other '%' (a literal
 * percent sign is %%). Errors (another conversion, two of them): FB_ERR_USAGE naming what. */
fb_result fb_frame_pattern(const char *what, const char *path, bool *has);

/* The pattern's path for frame `frame`, into out (size bytes). */
void fb_frame_path(const char *pattern, long frame, char *out, size_t size);

/* The JSON text of scene s at frame time `frame`, to parse (its canonical form is then the frame's
 * stored scene): every layer whose class has the key "time" set to it, the scene key "frames"
 * dropped; malloc'd into *out. Errors: FB_ERR_INPUT where no layer has a time (nothing would move). */
fb_result fb_frame_scene_json(const fb_scene *s, long frame, char **out);

/* Whether the frame at path is done: *done false where no file is there; true where one is and its
 * stored scene is `json`. Errors: FB_ERR_INPUT (one line) where a file is there holding another scene
 * or none (it is never replaced), or cannot be read. */
fb_result fb_frame_done(const char *path, const char *json, bool *done);

#endif
