#include "study/stimulus.h"

#include <ostream>

#include "io/config.h"

namespace rigidtouch::study {

void TextPresenter::Present(const Condition& condition, int taps) {
  out_ << "  [text presenter] rendering " << condition.label << " ("
       << text::RendererName(condition.renderer) << ") for " << taps << " tap"
       << (taps == 1 ? "" : "s") << "\n";
  out_.flush();
}

std::string TextPresenter::Describe() const {
  return "text presenter (dry run: prints the condition, renders nothing)";
}

}  // namespace rigidtouch::study
