#include "ui/jobs/sequence/relay_buttons.h"

#include <QBoxLayout>
#include <QPushButton>

namespace sp {

RelayButtons::RelayButtons(QWidget* parent) : QWidget(parent) {
  auto* layout = new QHBoxLayout(this);
  layout->setContentsMargins(0, 0, 0, 0);
  send_ = new QPushButton(tr("Send to robot"), this);
  send_->setToolTip(tr("Only a sequence that passed its rehearsal, unchanged since"));
  abort_ = new QPushButton(tr("Abort"), this);
  abort_->setToolTip(tr("Stop the sequence on the robot (the robot stops)"));
  layout->addWidget(send_);
  layout->addWidget(abort_);
  connect(send_, &QPushButton::clicked, this, &RelayButtons::sendClicked);
  connect(abort_, &QPushButton::clicked, this, &RelayButtons::abortClicked);
}

void RelayButtons::setStates(bool canSend, bool running) {
  send_->setEnabled(canSend && !running);
  abort_->setEnabled(running);
}

}  // namespace sp
