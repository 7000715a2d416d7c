// How stb_image and stb_image_write are compiled here (stb_impl.cpp holds
// their implementation; image_io.cpp calls them): JPEG and PNG only, no
// files, no float formats, at most 32768 pixels a side. image_io.cpp checks
// every byte stream before stb sees it (io.h: read_image).
#pragma once
#define STBI_NO_STDIO
#define STBI_FAILURE_USERMSG
#define STBI_ONLY_JPEG
#define STBI_ONLY_PNG
#define STBI_NO_LINEAR
#define STBI_NO_HDR
#define STBI_MAX_DIMENSIONS (1 << 15)
#define STBI_WRITE_NO_STDIO
