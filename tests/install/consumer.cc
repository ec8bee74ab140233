// Links the installed rigidtouch and runs one tick of a scene given on the command line, with one
// thread and with the worker thread of threads 2 (which needs the threads library at link time).
#include <rigidtouch/rigidtouch.h>

#include <iostream>

int main(int argc, char** argv) {
  if (argc < 2) return 2;
  long steps = 0;
  for (const int threads : {1, 2}) {
    rigidtouch::LoadOptions options;
    options.threads = threads;
    const rigidtouch::Model model = rigidtouch::LoadModel(argv[1], options);
    rigidtouch::Data data = rigidtouch::MakeData(model);
    rigidtouch::Tick(model, data, {});
    steps += data.step;
  }
  std::cout << "consumer ticked " << steps << " step(s) with 1 and 2 threads\n";
  return steps == 2 ? 0 : 1;
}
