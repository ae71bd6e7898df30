// page_assets.h — the preview page's files, embedded at build time from src/preview/page.html and
// page.js (cmake/EmbedText.cmake): the server serves these strings, never a file.
#pragma once

namespace clrt {

const char* previewPageHtml();
const char* previewPageJs();

}  // namespace clrt
