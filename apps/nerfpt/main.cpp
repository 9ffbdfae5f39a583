#include <cstdio>
int main() { std::puts("nerfpt"); return 0; }
