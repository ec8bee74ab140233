// Links the installed rigidtouch and runs one tick of a scene given on the command line.
#include <rigidtouch/rigidtouch.h>

#include <iostream>

int main(int argc, char** argv) {
  if (argc < 2) return 2;
  const rigidtouch::Model model = rigidtouch::LoadModel(argv[1], {});
  rigidtouch::Data data = rigidtouch::MakeData(model);
  rigidtouch::Tick(model, data, {});
  std::cout << "consumer ticked " << data.step << " step(s)\n";
  return data.step == 1 ? 0 : 1;
}
