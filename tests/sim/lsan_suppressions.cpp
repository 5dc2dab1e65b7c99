// LeakSanitizer (CAIRN_SANITIZE=ON) reports fontconfig's process-wide caches, which cairo's text
// drawing in sim/render.cpp fills once and never frees; they are not leaks of cairn's. LSan
// reads this hook at start-up; in other builds it is an unused function.

extern "C" const char* __lsan_default_suppressions();
extern "C" const char* __lsan_default_suppressions() { return "leak:libfontconfig.so\n"; }
