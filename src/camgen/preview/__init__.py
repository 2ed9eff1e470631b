"""Looking at a render before training on it: the annotations drawn over the frames (`draw`, pure functions on
arrays), what a render wrote read back (`source`), the preview's video and contact sheet (`run`) and its
self-contained HTML page (`page`)."""
